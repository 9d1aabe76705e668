"""The display: 00E0 and DXYN on the packed screen.

A screen row is 64 pixels in two uint32 words, x = 0 in bit 31 of word 0. A sprite byte drawn
at column x is that byte shifted into the 64-bit row, so a draw is shifts, an AND for the
collision test and an XOR, over the rows the sprite covers.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from octax_core.emulator.ops import Context, Effect
from octax_core.emulator.state import SCREEN_HEIGHT


def _shl(value, amount):
    # XLA defines shifts by >= 32 (and by negative amounts, seen as huge unsigned) as 0, which
    # is exactly "the byte slid off this word".
    return value << amount.astype(jnp.uint32)


def _shr(value, amount):
    return value >> amount.astype(jnp.uint32)


def sprite_rows(sprite: jax.Array, x: jax.Array, clipping: bool) -> jax.Array:
    """(rows,) sprite bytes at column x (0..63) -> (rows, 2) uint32 row words."""
    top = sprite.astype(jnp.uint32) << 24  # the byte in the top bits of a word: x = 0..7
    high_word = _shr(top, x)
    low_word = _shl(top, 32 - x) | _shr(top, x - 32)
    if not clipping:  # pixels past x = 63 come back at x = 0
        high_word = high_word | _shl(top, 64 - x)
    return jnp.stack([high_word, low_word], axis=-1)


def sprite_mask(aligned, x, y, height, clipping: bool) -> jax.Array:
    """The (32, 2) XOR mask of a `height`-row sprite at (x, y); all zero when height is 0.

    Args:
        aligned: the bytes at addresses I - y + r for r = 0..31 (and 32..63 without clipping),
            so that screen row r >= y shows sprite row r - y with no gather.
        x, y: the sprite's top-left corner, already reduced to 0..63 and 0..31.
        height: rows to draw, 0..15.
        clipping: cut at the bottom edge instead of wrapping to the top (static).
    """
    offset = jnp.arange(SCREEN_HEIGHT, dtype=jnp.int32) - y  # sprite row shown on each screen row
    if clipping:
        covered, row_bytes = (offset >= 0) & (offset < height), aligned[:SCREEN_HEIGHT]
    else:  # rows above y show the sprite rows that wrapped past the bottom
        covered = (offset & (SCREEN_HEIGHT - 1)) < height
        row_bytes = jnp.where(offset >= 0, aligned[:SCREEN_HEIGHT], aligned[SCREEN_HEIGHT:])
    return sprite_rows(jnp.where(covered, row_bytes, 0), x, clipping)


def collides(screen, mask) -> jax.Array:
    """Whether XORing `mask` onto `screen` turns a lit pixel off."""
    hits = jax.lax.reduce(screen & mask, jnp.uint32(0), jax.lax.bitwise_or, (0, 1))
    return hits != 0


def op_00e0(c: Context) -> Effect:
    """CLS."""
    return Effect(clear=jnp.bool_(True))


def op_dxyn(c: Context) -> Effect:
    """DRW Vx, Vy, n: XOR an n-row sprite from [I]; VF = collision."""
    return Effect(vf=c.collision.astype(jnp.int32))
