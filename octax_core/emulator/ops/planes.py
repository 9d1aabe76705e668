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


def sprite_mask(sprites, vx, vy, n, hires, plane, planes: int, clipping: bool, drawing):
    """The (planes, 64, 4) XOR mask of DXYN on the grid; all zero where `drawing` is false.

    The sprite is built in its own frame first (its rows, doubled in lores, already shifted to
    their grid column: 32 rows of 4 words), then dropped onto the screen rows with one
    `dynamic_update_slice`; the rows that fall past the bottom wrap to the top without clipping.

    Args:
        sprites: (planes, 32) int32, plane p's 32 bytes from its own start address (plane 1 at
            I; plane 2 right after plane 1's rows when both are selected, else at I too).
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
    pairs = sprites.reshape(planes, 16, 2)
    first = jnp.where(wide, pairs[..., 0], sprites[..., :16])  # (planes, 16): row j's bytes
    second = jnp.where(wide, pairs[..., 1], 0)
    selected = ((plane >> jnp.arange(planes, dtype=jnp.int32)) & 1) == 1
    shown = (jnp.arange(16) < height)[None, :] & selected[:, None] & drawing
    pattern = jnp.where(shown, (first << 8) | second, 0).astype(jnp.uint32)  # 16 bits, left first
    # Hires: 16 grid rows of 16 bits. Lores: each row twice, each bit twice: 32 rows of 32 bits.
    lores = jnp.repeat(double_bits(pattern), 2, axis=-1)
    hires_rows = jnp.concatenate([pattern << 16, jnp.zeros_like(pattern)], axis=-1)
    rows = jnp.where(hires, hires_rows, lores)  # (planes, 32)
    scale = jnp.where(hires, 1, 2)
    x0 = vx & jnp.where(hires, GRID_WIDTH - 1, GRID_WIDTH // 2 - 1)
    y0 = vy & jnp.where(hires, GRID_HEIGHT - 1, GRID_HEIGHT // 2 - 1)
    words = place(rows, x0 * scale, clipping)  # (planes, 32, 4)
    canvas = jnp.zeros((planes, GRID_HEIGHT + 32, WORDS), jnp.uint32)
    canvas = jax.lax.dynamic_update_slice(canvas, words, (0, y0 * scale, 0))
    if clipping:
        return canvas[:, :GRID_HEIGHT]
    wrapped = jnp.concatenate([canvas[:, GRID_HEIGHT:], jnp.zeros_like(canvas[:, 32:GRID_HEIGHT])], axis=1)
    return canvas[:, :GRID_HEIGHT] | wrapped


def collides(screen, mask) -> jax.Array:
    """Whether XORing `mask` onto the planes turns a lit pixel off."""
    return jnp.any((screen & mask) != 0)


def scroll(screen, dx, dy):
    """The (planes, 64, 4) planes moved dx grid pixels right and dy down (negative: left, up);
    what comes in is dark. |dx| < 32, |dy| < 64.

    Across, a funnel shift of each word with its neighbours (a shift by an out-of-range amount
    is 0, so the terms of the other direction vanish); down, a take of rows. Measured under
    vmap on a CPU, this is twice as fast as slicing a zero-padded copy.
    """
    zero = jnp.zeros_like(screen[..., :1])
    before = jnp.concatenate([zero, screen[..., :-1]], axis=-1)  # the word to the left
    after = jnp.concatenate([screen[..., 1:], zero], axis=-1)  # the word to the right
    moved = _shr(screen, dx) | _shl(screen, -dx) | _shl(before, 32 - dx) | _shr(after, 32 + dx)
    source = jnp.arange(GRID_HEIGHT, dtype=jnp.int32) - dy
    inside = (source >= 0) & (source < GRID_HEIGHT)
    rows = jnp.take(moved, jnp.clip(source, 0, GRID_HEIGHT - 1), axis=-2)
    return jnp.where(inside[:, None], rows, jnp.uint32(0))
