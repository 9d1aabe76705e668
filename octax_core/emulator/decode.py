"""Opcode decoding: bit slicing plus one lookup table that names each opcode's kind.

The table is data, not an if-chain (fogleman/nes keeps its 256-entry instruction tables the same
way): `KIND_TABLE[opcode >> 12, opcode & 0xFF]` gives the instruction kind; only 0x0XNN needs X
as well (00E0 and 00EE exist, 01E0 does not).
"""

from __future__ import annotations

import enum
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np


class Kind(enum.IntEnum):
    """Every instruction the machine distinguishes. NOP covers unknown opcodes."""

    NOP = 0  # unknown / unsupported opcode: pc += 2
    STALL = enum.auto()  # not an opcode: the frame already ended (display wait), pc stays
    CLS = enum.auto()  # 00E0
    RET = enum.auto()  # 00EE
    JP = enum.auto()  # 1NNN
    CALL = enum.auto()  # 2NNN
    SE_NN = enum.auto()  # 3XNN
    SNE_NN = enum.auto()  # 4XNN
    SE_XY = enum.auto()  # 5XY0
    LD_NN = enum.auto()  # 6XNN
    ADD_NN = enum.auto()  # 7XNN
    LD_XY = enum.auto()  # 8XY0
    OR = enum.auto()  # 8XY1
    AND = enum.auto()  # 8XY2
    XOR = enum.auto()  # 8XY3
    ADD_XY = enum.auto()  # 8XY4
    SUB = enum.auto()  # 8XY5
    SHR = enum.auto()  # 8XY6
    SUBN = enum.auto()  # 8XY7
    SHL = enum.auto()  # 8XYE
    SNE_XY = enum.auto()  # 9XY0
    LD_I = enum.auto()  # ANNN
    JP_V = enum.auto()  # BNNN
    RND = enum.auto()  # CXNN
    DRW = enum.auto()  # DXYN
    SKP = enum.auto()  # EX9E
    SKNP = enum.auto()  # EXA1
    LD_VX_DT = enum.auto()  # FX07
    LD_KEY = enum.auto()  # FX0A
    LD_DT = enum.auto()  # FX15
    LD_ST = enum.auto()  # FX18
    ADD_I = enum.auto()  # FX1E
    LD_FONT = enum.auto()  # FX29
    BCD = enum.auto()  # FX33
    STORE = enum.auto()  # FX55
    LOAD = enum.auto()  # FX65


def _build_kind_table() -> np.ndarray:
    table = np.full((16, 256), Kind.NOP, np.uint8)
    table[0x0, 0xE0], table[0x0, 0xEE] = Kind.CLS, Kind.RET
    for top, kind in [(1, Kind.JP), (2, Kind.CALL), (3, Kind.SE_NN), (4, Kind.SNE_NN),
                      (6, Kind.LD_NN), (7, Kind.ADD_NN), (0xA, Kind.LD_I), (0xB, Kind.JP_V),
                      (0xC, Kind.RND), (0xD, Kind.DRW)]:
        table[top, :] = kind
    low_nibble = np.arange(256) & 0xF
    table[0x5, low_nibble == 0] = Kind.SE_XY
    table[0x9, low_nibble == 0] = Kind.SNE_XY
    alu = {0: Kind.LD_XY, 1: Kind.OR, 2: Kind.AND, 3: Kind.XOR, 4: Kind.ADD_XY,
           5: Kind.SUB, 6: Kind.SHR, 7: Kind.SUBN, 0xE: Kind.SHL}
    for n, kind in alu.items():
        table[0x8, low_nibble == n] = kind
    table[0xE, 0x9E], table[0xE, 0xA1] = Kind.SKP, Kind.SKNP
    for nn, kind in [(0x07, Kind.LD_VX_DT), (0x0A, Kind.LD_KEY), (0x15, Kind.LD_DT),
                     (0x18, Kind.LD_ST), (0x1E, Kind.ADD_I), (0x29, Kind.LD_FONT),
                     (0x33, Kind.BCD), (0x55, Kind.STORE), (0x65, Kind.LOAD)]:
        table[0xF, nn] = kind
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
