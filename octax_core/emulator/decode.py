"""Opcode decoding: bit slicing plus one lookup table that names each opcode's kind.

The table is data, not an if-chain (fogleman/nes keeps its 256-entry instruction tables the same
way), built from `opcodes.OPCODES`, the one list of opcodes that the disassembler reads too.
CHIP-8 and SUPER-CHIP read `kind_table(level)[opcode >> 12, opcode & 0xFF]` (4 KB); only 0x0XNN
needs X as well (00E0 and 00EE exist, 01E0 does not). XO-CHIP has opcodes that need X too (F000,
F002, FN01 with N in 0..3), so it reads one entry per 16-bit word (`word_table`, 64 KB).
"""

from __future__ import annotations

import functools
from typing import NamedTuple, Union

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.opcodes import LEVELS, OPCODES, Kind, lookup
from octax_core.emulator.platforms import PLATFORMS, Platform, resolve_platform

__all__ = ["Decoded", "KIND_TABLE", "Kind", "decode", "word_table"]


@functools.lru_cache(maxsize=None)
def kind_table(level: int) -> np.ndarray:
    """The kind of every (top nibble, low byte) pair on a platform of `level`, read with X = 0
    (`decode` makes 0X__ with X != 0 a NOP). Enough for CHIP-8 and SUPER-CHIP, whose opcodes
    never depend on X otherwise; XO-CHIP's F000, F002 and FN01 do (`word_table`)."""
    table = np.full((16, 256), Kind.NOP, np.uint8)
    for top in range(16):
        for low in range(256):
            row = lookup(top << 12 | low)
            if row is not None and row.kind is not None and LEVELS[row.platform] <= level:
                table[top, low] = row.kind
    table.flags.writeable = False
    return table


KIND_TABLE = kind_table(0)  # CHIP-8's, (16, 256) uint8, numpy: no device array at import
SMALL_TABLE_LEVELS = (0, 1)  # the levels `kind_table` decodes exactly (tests/core_emulator/test_decode.py)


@functools.lru_cache(maxsize=None)
def word_table(platform: str) -> np.ndarray:
    """(65536,) uint8: the kind a `platform` machine runs each 16-bit word as (`opcodes.kind_on`).

    Filled row by row, last row first, so that the first matching row wins, as in `lookup`.
    """
    words = np.arange(0x10000, dtype=np.uint32)
    table = np.full(0x10000, Kind.NOP, np.uint8)
    for row in reversed(OPCODES):
        known = row.kind is not None and LEVELS[row.platform] <= LEVELS[platform]
        table[(words & row.mask) == row.pattern] = row.kind if known else Kind.NOP
    table.flags.writeable = False
    return table


class Decoded(NamedTuple):
    """The fields of one opcode, all int32 scalars."""

    kind: jax.Array
    x: jax.Array
    y: jax.Array
    n: jax.Array
    nn: jax.Array
    nnn: jax.Array


def decode(high: jax.Array, low: jax.Array, platform: Union[Platform, str] = PLATFORMS["chip8"]) -> Decoded:
    """Splits the two opcode bytes into fields and looks up the instruction kind on `platform`
    (a `Platform`, or its name as `Machine` takes it)."""
    platform = resolve_platform(platform)
    high, low = high.astype(jnp.int32), low.astype(jnp.int32)
    top, x = high >> 4, high & 0xF
    if platform.level in SMALL_TABLE_LEVELS:  # 4 KB: the lookup stays in cache
        kind = jnp.asarray(kind_table(platform.level).reshape(-1))[top * 256 + low].astype(jnp.int32)
        kind = jnp.where((top == 0) & (x != 0), int(Kind.NOP), kind)  # 0NNN machine-code calls
    else:
        kind = jnp.asarray(word_table(platform.name))[high * 256 + low].astype(jnp.int32)
    return Decoded(kind=kind, x=x, y=low >> 4, n=low & 0xF, nn=low, nnn=(x << 8) | low)
