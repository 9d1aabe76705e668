"""Keypad: EX9E, EXA1 and the blocking FX0A."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from octax_core.emulator.ops import Context, Effect, next_pc
from octax_core.emulator.state import NO_KEY


def is_held(keys, key) -> jax.Array:
    """Whether `key` (0..15) is set in the uint32 mask `keys`."""
    return ((keys >> key.astype(jnp.uint32)) & 1) == 1


def op_ex9e(c: Context) -> Effect:
    """SKP Vx: skip if key Vx is held."""
    return Effect(pc=next_pc(c, is_held(c.keys, c.vx & 0xF)))


def op_exa1(c: Context) -> Effect:
    """SKNP Vx: skip if key Vx is not held."""
    return Effect(pc=next_pc(c, ~is_held(c.keys, c.vx & 0xF)))


def _lowest_key(keys) -> jax.Array:
    lowest_bit = keys & (~keys + 1)
    return (31 - jax.lax.clz(lowest_bit)).astype(jnp.int32)


def op_fx0a(c: Context) -> Effect:
    """LD Vx, K: wait for a key to be pressed and released (COSMAC VIP), then Vx = key."""
    seen = c.key_wait != NO_KEY
    released = seen & ~is_held(c.keys, c.key_wait)
    first_press = jnp.where(c.keys != 0, _lowest_key(c.keys), NO_KEY)
    key_wait = jnp.where(released, NO_KEY, jnp.where(seen, c.key_wait, first_press))
    return Effect(vx=jnp.where(released, c.key_wait, c.vx), pc=c.pc + 2 * released.astype(c.pc.dtype),
                  key_wait=key_wait)
