"""The 60 Hz delay and sound timers as registers: FX07, FX15, FX18."""

from __future__ import annotations

from octax_core.emulator.ops import Context


def op_fx07(c: Context) -> dict:
    """LD Vx, DT."""
    return {"vx": c.delay_timer}


def op_fx15(c: Context) -> dict:
    """LD DT, Vx."""
    return {"delay_timer": c.vx}


def op_fx18(c: Context) -> dict:
    """LD ST, Vx."""
    return {"sound_timer": c.vx}
