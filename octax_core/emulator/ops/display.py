"""The display: packed bit surfaces, sprites XORed onto them, clears and scrolls.

A surface is (..., rows, words) uint32: pixel x of a row is bit 31 - x % 32 of word x // 32, so
a sprite row drawn at column x is its bits shifted into the row's words, a draw is shifts, an
AND for the collision test and an XOR, and the same `state.unpack_screen` reads every surface.

Two sizes, one code: the 64x32 surface (32 rows of 2 words) and the 128x64 one (64 rows of 4).
CHIP-8's screen is one 64x32 surface. SUPER-CHIP and XO-CHIP have both, per plane: the lores
picture stays at lores size in the 64x32 `screen`, the hires one in the 128x64 `grid`. Switching
mode clears every plane, so one of the two is always dark, a lores picture is always made of
whole lores pixels, and `state.display` doubles it for viewing. A lores machine of any platform
therefore draws, clears and scrolls a 64x32 surface, as CHIP-8 does; only hires work touches
the grid.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.ops import Context, Effect
from octax_core.emulator.quirks import choose

LORES = (32, 2)  # rows, words: the 64x32 surface
HIRES = (64, 4)  # the 128x64 grid
ALL_PLANES = 3


def _shl(value, amount):
    # XLA defines shifts by >= 32 (and by negative amounts, seen as huge unsigned) as 0, which
    # is exactly "the bits slid off this word".
    return value << jnp.asarray(amount).astype(jnp.uint32)


def _shr(value, amount):
    return value >> jnp.asarray(amount).astype(jnp.uint32)


def sprite_patterns(data, n, wide_sprites: bool):
    """A sprite's rows as 16-pixel patterns, leftmost pixel in bit 31, and its height.

    Args:
        data: (..., 16) bytes (any integer dtype) at the sprite's address; (..., 32) where `wide_sprites`.
        n: the opcode's N: the height, or 0 for SUPER-CHIP's 16x16 sprite (two bytes a row).
        wide_sprites: whether N = 0 means 16x16 (SUPER-CHIP and XO-CHIP; static). On CHIP-8
            it means no rows.

    Returns:
        ((..., 16) uint32 rows, int32 height).
    """
    narrow = data[..., :16].astype(jnp.uint32) << 24
    if not wide_sprites:
        return narrow, n
    pairs = data.reshape(*data.shape[:-1], 16, 2).astype(jnp.uint32)
    wide = n == 0
    return jnp.where(wide, ((pairs[..., 0] << 8) | pairs[..., 1]) << 16, narrow), jnp.where(wide, 16, n)


def place(rows, x0, words: int, clipping: bool):
    """(...,) row patterns (leftmost pixel in bit 31) -> (..., words) words with the pattern at
    column x0 of a surface `words` words wide. With clipping the pixels past the right edge are
    lost; without, they come back at column 0."""
    k32 = jnp.arange(words, dtype=jnp.int32) * 32
    rows = rows[..., None]
    out = _shr(rows, x0 - k32) | _shl(rows, k32 - x0)
    if clipping is not True:
        wrapped = _shl(rows, k32 + 32 * words - x0)
        out = out | (wrapped if clipping is False else jnp.where(clipping, jnp.uint32(0), wrapped))
    return out


def sprite_mask(patterns, x0, y0, height, surface: tuple[int, int], clipping: bool):
    """The XOR mask of a sprite drawn at (x0, y0) on a `surface` (rows, words): (..., rows, words).

    Screen row r shows sprite row (r - y0), if that row is below `height`; without clipping the
    rows past the bottom come back at the top. The rows are picked with one small gather, so
    the work is the surface's rows, never the memory's.
    """
    rows, words = surface
    offset = jnp.arange(rows, dtype=jnp.int32) - y0
    covered = choose(clipping, (offset >= 0) & (offset < height), (offset & (rows - 1)) < height)
    # Row r shows pattern (r - y0) mod 16: a window of the patterns repeated, one slice per
    # machine (a contiguous gather under vmap, which XLA keeps as its own small buffer, so the
    # shifts that follow are all the collision test and the XOR recompute).
    tiled = jnp.tile(patterns, rows // 16 + 1)
    shown = jax.lax.dynamic_slice_in_dim(tiled, 16 - (y0 & 15), rows, axis=-1)
    return place(jnp.where(covered, shown, jnp.uint32(0)), x0, words, clipping)



def collides(surface, mask) -> jax.Array:
    """Whether XORing `mask` onto `surface` turns a lit pixel off."""
    hits = jax.lax.reduce(surface & mask, jnp.uint32(0), jax.lax.bitwise_or, tuple(range(surface.ndim)))
    return hits != 0


def scroll(surface, dx, dy):
    """The (..., rows, words) surface moved dx pixels right and dy down (negative: left, up);
    what comes in is dark. |dx| < 32, |dy| < rows.

    Across, a funnel shift of each word with its neighbours (a shift by an out-of-range amount
    is 0, so the terms of the other direction vanish); down, a take of rows.
    """
    rows = surface.shape[-2]
    zero = jnp.zeros_like(surface[..., :1])
    before = jnp.concatenate([zero, surface[..., :-1]], axis=-1)  # the word to the left
    after = jnp.concatenate([surface[..., 1:], zero], axis=-1)  # the word to the right
    moved = _shr(surface, dx) | _shl(surface, -dx) | _shl(before, 32 - dx) | _shr(after, 32 + dx)
    source = jnp.arange(rows, dtype=jnp.int32) - dy
    inside = (source >= 0) & (source < rows)
    taken = jnp.take(moved, jnp.clip(source, 0, rows - 1), axis=-2)
    return jnp.where(inside[:, None], taken, jnp.uint32(0))


def double_bits(half):
    """16 bits (uint32, in the low half) -> 32 bits with every bit twice; numpy or JAX."""
    v = half
    for shift, mask in ((8, 0x00FF00FF), (4, 0x0F0F0F0F), (2, 0x33333333), (1, 0x55555555)):
        v = (v | (v << shift)) & mask
    return v | (v << 1)


def upscale(lores):
    """(..., 32, 2) 64x32 surfaces -> (..., 64, 4): every pixel a 2x2 block. numpy or JAX."""
    xp = jnp if isinstance(lores, jax.Array) else np
    lores = xp.asarray(lores, xp.uint32)
    halves = xp.stack([lores >> 16, lores & 0xFFFF], axis=-1).reshape(*lores.shape[:-1], 4)
    return xp.repeat(double_bits(halves), 2, axis=-2)


def op_00e0(c: Context) -> Effect:
    """CLS: clear the selected planes (CHIP-8 and SUPER-CHIP: the one plane)."""
    return Effect(clear_planes=c.plane)


def op_dxyn(c: Context) -> Effect:
    """DRW Vx, Vy, n: XOR an n-row sprite from [I] (n = 0: 16x16 after CHIP-8); VF = 1 if any
    lit pixel of any plane was erased."""
    return Effect(vf=c.collision.astype(jnp.int32))
