"""The 60 Hz delay and sound timers as registers: FX07, FX15, FX18."""

from __future__ import annotations

from octax_core.emulator.ops import Context, Effect


def op_fx07(c: Context) -> Effect:
    """LD Vx, DT."""
    return Effect(vx=c.delay_timer)


def op_fx15(c: Context) -> Effect:
    """LD DT, Vx."""
    return Effect(delay_timer=c.vx)


def op_fx18(c: Context) -> Effect:
    """LD ST, Vx."""
    return Effect(sound_timer=c.vx)
