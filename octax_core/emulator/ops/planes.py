"""The SUPER-CHIP / XO-CHIP display: bit planes of 64 rows x 128 pixels, each row 4 uint32 words.

One grid serves both modes: in hires a screen pixel is a grid pixel; in lores (64x32) it is a 2x2
block, so a lores sprite is drawn with every bit doubled across and every row doubled down, and
a lores scroll moves twice as many grid pixels. Pixel gx of a row is bit 31 - gx % 32 of word
gx // 32, as on CHIP-8's screen, so the same `unpack_screen` reads both.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from octax_core.emulator.state import GRID_HEIGHT, GRID_WIDTH

WORDS = GRID_WIDTH // 32


def _shl(value, amount):
    # XLA defines shifts by >= 32 (and by negative amounts, seen as huge unsigned) as 0.
    return value << jnp.asarray(amount).astype(jnp.uint32)


def _shr(value, amount):
    return value >> jnp.asarray(amount).astype(jnp.uint32)


def double_bits(pattern):
    """A 16-bit row (uint32) -> 32 bits with every bit twice: a lores row on the hires grid."""
    v = pattern
    v = (v | (v << 8)) & jnp.uint32(0x00FF00FF)
    v = (v | (v << 4)) & jnp.uint32(0x0F0F0F0F)
    v = (v | (v << 2)) & jnp.uint32(0x33333333)
    v = (v | (v << 1)) & jnp.uint32(0x55555555)
    return v | (v << 1)


def place(rows, gx, clipping: bool):
    """(..., 64) uint32 rows whose pixels start at bit 31 -> (..., 64, 4) words at grid column gx.

    With clipping the pixels past column 127 are lost; without, they come back at column 0.
    """
    k32 = jnp.arange(WORDS, dtype=jnp.int32) * 32
    rows = rows[..., None]
    words = _shr(rows, gx - k32) | _shl(rows, k32 - gx)
    if not clipping:
        words = words | _shl(rows, k32 + GRID_WIDTH - gx)
    return words


def sprite_mask(sprite, vx, vy, n, hires, plane, planes: int, clipping: bool, drawing):
    """The (planes, 64, 4) XOR mask of DXYN on the grid; all zero where `drawing` is false.

    Args:
        sprite: (64,) int32, the bytes at I..I+63: plane 1's rows, then plane 2's when both
            planes are selected (a 16x16 sprite is 32 bytes, two a row).
        vx, vy: the registers; taken modulo the screen size of the mode.
        n: the sprite height, 0 meaning 16 rows of 16 pixels.
        hires: bool, 128x64 mode.
        plane: the selected planes, 0..3 (bit p: plane p + 1).
        planes: planes of the display (static: 1 or 2).
        clipping: cut at the right and bottom edges instead of wrapping (static).
        drawing: bool, whether this instruction is a DXYN.
    """
    wide = n == 0
    height = jnp.where(wide, 16, n)
    row_bytes = jnp.where(wide, 2, 1)
    screen_height = jnp.where(hires, GRID_HEIGHT, GRID_HEIGHT // 2)
    x0 = vx & jnp.where(hires, GRID_WIDTH - 1, GRID_WIDTH // 2 - 1)
    y0 = vy & (screen_height - 1)
    grid_row = jnp.arange(GRID_HEIGHT, dtype=jnp.int32)
    offset = jnp.where(hires, grid_row, grid_row >> 1) - y0  # sprite row on each screen row
    if clipping:
        covered = (offset >= 0) & (offset < height)
    else:
        offset = offset & (screen_height - 1)
        covered = offset < height
    plane_index = jnp.arange(planes, dtype=jnp.int32)
    selected = ((plane >> plane_index) & 1) == 1
    # Plane 2's rows follow plane 1's when plane 1 is drawn too.
    base = jnp.where(plane_index == 1, (plane & 1) * height * row_bytes, 0)
    index = jnp.clip(base[:, None] + offset[None, :] * row_bytes, 0, sprite.shape[-1] - 2)
    first, second = sprite[index], sprite[index + 1]
    pattern = (first << 8) | jnp.where(wide, second, 0)
    pattern = jnp.where(covered[None, :] & selected[:, None] & drawing, pattern, 0).astype(jnp.uint32)
    rows = jnp.where(hires, pattern << 16, double_bits(pattern))
    return place(rows, jnp.where(hires, x0, 2 * x0), clipping)


def collides(screen, mask) -> jax.Array:
    """Whether XORing `mask` onto the planes turns a lit pixel off."""
    return jnp.any((screen & mask) != 0)


def scroll(screen, dx, dy):
    """The (planes, 64, 4) planes moved dx grid pixels right and dy down (negative: left, up);
    what comes in is dark. |dx| < 32, |dy| < 64."""
    zero = jnp.zeros_like(screen[..., :1])
    before = jnp.concatenate([zero, screen[..., :-1]], axis=-1)  # the word to the left
    after = jnp.concatenate([screen[..., 1:], zero], axis=-1)  # the word to the right
    right = _shr(screen, dx) | _shl(before, 32 - dx)
    left = _shl(screen, -dx) | _shr(after, 32 + dx)
    moved = jnp.where(dx > 0, right, jnp.where(dx < 0, left, screen))
    dark = jnp.zeros_like(moved)
    tall = jnp.concatenate([dark, moved, dark], axis=-2)
    start = (0,) * (screen.ndim - 2) + (GRID_HEIGHT - dy, 0)
    return jax.lax.dynamic_slice(tall, start, screen.shape)
