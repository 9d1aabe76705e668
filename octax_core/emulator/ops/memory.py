"""The index register and memory transfers: ANNN, FX1E, FX29, FX33, FX55, FX65."""

from __future__ import annotations

import jax.numpy as jnp

from octax_core.emulator.ops import Context
from octax_core.emulator.state import FONT_ADDRESS


def op_annn(c: Context) -> dict:
    """LD I, nnn."""
    return {"i": c.nnn}


def op_fx1e(c: Context) -> dict:
    """ADD I, Vx; VF untouched."""
    return {"i": c.I + c.vx}


def op_fx29(c: Context) -> dict:
    """LD F, Vx: I = address of the font glyph for the low nibble of Vx."""
    return {"i": FONT_ADDRESS + 5 * (c.vx & 0xF)}


def op_fx33(c: Context) -> dict:
    """LD B, Vx: memory[I..I+2] = decimal digits of Vx."""
    digits = jnp.stack([c.vx // 100, (c.vx // 10) % 10, c.vx % 10])
    return {"mem_data": jnp.pad(digits, (0, 13)), "mem_count": jnp.int32(3)}


def _after_transfer(c: Context) -> dict:
    return {"i": c.I + c.x + 1} if c.quirks.memory_increment else {}


def op_fx55(c: Context) -> dict:
    """LD [I], V0..Vx; I += x + 1 with memory_increment."""
    return {"mem_data": c.V, "mem_count": c.x + 1, **_after_transfer(c)}


def op_fx65(c: Context) -> dict:
    """LD V0..Vx, [I]; I += x + 1 with memory_increment."""
    # vx is named too: the effect writes Vx after the bulk load and must not undo it.
    return {"load_count": c.x + 1, "vx": c.window[c.x], **_after_transfer(c)}
