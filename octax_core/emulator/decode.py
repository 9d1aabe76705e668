"""Opcode decoding: bit slicing plus one lookup table that names each opcode's kind.

The table is data, not an if-chain (fogleman/nes keeps its 256-entry instruction tables the same
way): `KIND_TABLE[opcode >> 12, opcode & 0xFF]` gives the instruction kind; only 0x0XNN needs X
as well (00E0 and 00EE exist, 01E0 does not). It is built from `opcodes.OPCODES`, the one list of
opcodes that the disassembler reads too.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.opcodes import Kind, lookup

__all__ = ["Decoded", "KIND_TABLE", "Kind", "decode"]


def _build_kind_table() -> np.ndarray:
    """The kind of every (top nibble, low byte) pair, read with X = 0 (`decode` handles 0X__)."""
    table = np.full((16, 256), Kind.NOP, np.uint8)
    for top in range(16):
        for low in range(256):
            row = lookup(top << 12 | low)
            if row is not None and row.kind is not None:
                table[top, low] = row.kind
    return table


KIND_TABLE = _build_kind_table()  # (16, 256) uint8, numpy: no device array at import


class Decoded(NamedTuple):
    """The fields of one opcode, all int32 scalars."""

    kind: jax.Array
    x: jax.Array
    y: jax.Array
    n: jax.Array
    nn: jax.Array
    nnn: jax.Array


def decode(high: jax.Array, low: jax.Array) -> Decoded:
    """Splits the two opcode bytes into fields and looks up the instruction kind."""
    high, low = high.astype(jnp.int32), low.astype(jnp.int32)
    top, x = high >> 4, high & 0xF
    kind = jnp.asarray(KIND_TABLE.reshape(-1))[top * 256 + low].astype(jnp.int32)
    kind = jnp.where((top == 0) & (x != 0), int(Kind.NOP), kind)  # 0NNN machine-code calls
    return Decoded(kind=kind, x=x, y=low >> 4, n=low & 0xF, nn=low, nnn=(x << 8) | low)
