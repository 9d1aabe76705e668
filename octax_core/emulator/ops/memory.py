"""The index register and memory transfers: ANNN, FX1E, FX29, FX33, FX55, FX65."""

from __future__ import annotations

import jax.numpy as jnp

from octax_core.emulator.ops import Context, Effect
from octax_core.emulator.state import FONT_ADDRESS


def op_annn(c: Context) -> Effect:
    """LD I, nnn."""
    return Effect(i=c.nnn)


def op_fx1e(c: Context) -> Effect:
    """ADD I, Vx; VF untouched."""
    return Effect(i=c.I + c.vx)


def op_fx29(c: Context) -> Effect:
    """LD F, Vx: I = address of the font glyph for the low nibble of Vx."""
    return Effect(i=FONT_ADDRESS + 5 * (c.vx & 0xF))


def op_fx33(c: Context) -> Effect:
    """LD B, Vx: memory[I..I+2] = decimal digits of Vx."""
    digits = jnp.stack([c.vx // 100, (c.vx // 10) % 10, c.vx % 10])
    return Effect(mem_data=jnp.pad(digits, (0, 13)), mem_count=jnp.int32(3))


def _i_after_transfer(c: Context):
    """I after FX55/FX65: advanced by X + 1 with memory_increment, else untouched (None)."""
    if isinstance(c.quirks.memory_increment, bool):
        return c.I + c.x + 1 if c.quirks.memory_increment else None
    return jnp.where(c.quirks.memory_increment, c.I + c.x + 1, c.I)  # a mix of profiles


def op_fx55(c: Context) -> Effect:
    """LD [I], V0..Vx; I += x + 1 with memory_increment."""
    return Effect(mem_data=c.V, mem_count=c.x + 1, i=_i_after_transfer(c))


def op_fx65(c: Context) -> Effect:
    """LD V0..Vx, [I]; I += x + 1 with memory_increment."""
    return Effect(load_count=c.x + 1, i=_i_after_transfer(c))
