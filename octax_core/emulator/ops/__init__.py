"""Instruction handlers, one tiny function per opcode, grouped by family.

A handler takes the `Context` of the instruction being executed and returns an effect: a dict
holding only the fields it changes (`octax_core.emulator.cpu.EFFECT_FIELDS` lists them). Handlers never
build a state; `octax_core.emulator.cpu` merges the effects field by field and applies the result once,
so under `vmap` each field pays for a few scalar selects instead of every handler copying 4 KB
of memory.
"""

from __future__ import annotations

from typing import NamedTuple

import jax

from octax_core.emulator.quirks import Quirks


class Context(NamedTuple):
    """What a handler may read: decoded fields and the registers it needs, as int32 scalars."""

    quirks: Quirks  # static
    x: jax.Array
    y: jax.Array
    n: jax.Array
    nn: jax.Array
    nnn: jax.Array
    vx: jax.Array
    vy: jax.Array
    v0: jax.Array
    pc: jax.Array
    I: jax.Array
    sp: jax.Array
    stack_top: jax.Array  # stack[(sp - 1) mod 16]
    V: jax.Array  # (16,) int32, all registers
    window: jax.Array  # (16,) int32: memory[I .. I + 15], wrapping
    collision: jax.Array  # bool: the sprite of this DXYN would erase a lit pixel
    keys: jax.Array  # uint32 mask of held keys, bit k = key k
    delay_timer: jax.Array
    rng: jax.Array  # uint32
    key_wait: jax.Array


def next_pc(c: Context, skip) -> jax.Array:
    """The address after this instruction, or after the next one when `skip` holds."""
    return c.pc + 2 + 2 * skip.astype(c.pc.dtype)
