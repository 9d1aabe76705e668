"""Every CHIP-8, SUPER-CHIP and XO-CHIP opcode, once, as data.

One row per opcode: the bits that identify it (`mask`, `pattern`: a word is that opcode when
`word & mask == pattern`; the first matching row wins), the `Kind` the emulator runs it as (None
for a word it does not run: 0NNN machine-code calls), the platform that introduced it (on an
earlier platform the word is an unknown opcode, a no-op: `kind_on`), the Octo statement that writes it and
where execution may go next (`Flow`). The decoder (`decode.KIND_TABLE`) and the disassembler
(`octax_core.tools.octo.disassembler`) both read this table, so a new opcode is one row here.
"""

from __future__ import annotations

import enum
from typing import NamedTuple, Optional


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
    # SUPER-CHIP
    SCROLL_DOWN = enum.auto()  # 00CN
    SCROLL_RIGHT = enum.auto()  # 00FB
    SCROLL_LEFT = enum.auto()  # 00FC
    EXIT = enum.auto()  # 00FD
    LORES = enum.auto()  # 00FE
    HIRES = enum.auto()  # 00FF
    LD_BIG_FONT = enum.auto()  # FX30
    SAVE_FLAGS = enum.auto()  # FX75
    LOAD_FLAGS = enum.auto()  # FX85
    # XO-CHIP
    SCROLL_UP = enum.auto()  # 00DN
    SAVE_RANGE = enum.auto()  # 5XY2
    LOAD_RANGE = enum.auto()  # 5XY3
    LD_I_LONG = enum.auto()  # F000 NNNN
    PLANE = enum.auto()  # FN01
    AUDIO = enum.auto()  # F002
    PITCH = enum.auto()  # FX3A


class Flow(enum.Enum):
    """Where execution may go after an instruction, and what its address operand points at."""

    NEXT = enum.auto()  # the next instruction
    STOP = enum.auto()  # nowhere we can follow: return, exit
    JUMP = enum.auto()  # the target only
    CALL = enum.auto()  # the target, then the next instruction
    SKIP = enum.auto()  # the next instruction or the one after it
    JUMP0 = enum.auto()  # target + v0: unknown, so the path ends; the target still gets a label
    INDEX = enum.auto()  # the next instruction; the target is data (i := target)


class Opcode(NamedTuple):
    """One opcode. `octo` uses the fields {x} {y} (registers), {xn} {n} (numbers), {nn} {nnn}
    (hex) and {target} (a label or an address); None means Octo writes no statement for it."""

    mask: int
    pattern: int
    kind: Optional[Kind]
    platform: str  # "chip8", "schip" or "xochip": the first platform with this opcode
    octo: Optional[str]
    flow: Optional[Flow]


_C, _S, _X = "chip8", "schip", "xochip"

OPCODES: tuple[Opcode, ...] = (
    Opcode(0xFFFF, 0x00E0, Kind.CLS, _C, "clear", Flow.NEXT),
    Opcode(0xFFFF, 0x00EE, Kind.RET, _C, "return", Flow.STOP),
    Opcode(0xFFF0, 0x00C0, Kind.SCROLL_DOWN, _S, "scroll-down {n}", Flow.NEXT),
    Opcode(0xFFF0, 0x00D0, Kind.SCROLL_UP, _X, "scroll-up {n}", Flow.NEXT),
    Opcode(0xFFFF, 0x00FB, Kind.SCROLL_RIGHT, _S, "scroll-right", Flow.NEXT),
    Opcode(0xFFFF, 0x00FC, Kind.SCROLL_LEFT, _S, "scroll-left", Flow.NEXT),
    Opcode(0xFFFF, 0x00FD, Kind.EXIT, _S, "exit", Flow.STOP),
    Opcode(0xFFFF, 0x00FE, Kind.LORES, _S, "lores", Flow.NEXT),
    Opcode(0xFFFF, 0x00FF, Kind.HIRES, _S, "hires", Flow.NEXT),
    Opcode(0xFFFF, 0x0000, None, _C, None, None),  # 0000 is padding far more often than a machine-code call
    Opcode(0xF000, 0x0000, None, _C, "native {nnn}", Flow.NEXT),  # machine code: the emulator skips it
    Opcode(0xF000, 0x1000, Kind.JP, _C, "jump {target}", Flow.JUMP),
    Opcode(0xF000, 0x2000, Kind.CALL, _C, "{target}", Flow.CALL),  # a bare label name is a call in Octo
    Opcode(0xF000, 0x3000, Kind.SE_NN, _C, "if {x} != {nn} then", Flow.SKIP),  # `if C then S` skips S when C is false
    Opcode(0xF000, 0x4000, Kind.SNE_NN, _C, "if {x} == {nn} then", Flow.SKIP),
    Opcode(0xF00F, 0x5000, Kind.SE_XY, _C, "if {x} != {y} then", Flow.SKIP),
    Opcode(0xF00F, 0x5002, Kind.SAVE_RANGE, _X, "save {x} - {y}", Flow.NEXT),
    Opcode(0xF00F, 0x5003, Kind.LOAD_RANGE, _X, "load {x} - {y}", Flow.NEXT),
    Opcode(0xF000, 0x6000, Kind.LD_NN, _C, "{x} := {nn}", Flow.NEXT),
    Opcode(0xF000, 0x7000, Kind.ADD_NN, _C, "{x} += {nn}", Flow.NEXT),
    Opcode(0xF00F, 0x8000, Kind.LD_XY, _C, "{x} := {y}", Flow.NEXT),
    Opcode(0xF00F, 0x8001, Kind.OR, _C, "{x} |= {y}", Flow.NEXT),
    Opcode(0xF00F, 0x8002, Kind.AND, _C, "{x} &= {y}", Flow.NEXT),
    Opcode(0xF00F, 0x8003, Kind.XOR, _C, "{x} ^= {y}", Flow.NEXT),
    Opcode(0xF00F, 0x8004, Kind.ADD_XY, _C, "{x} += {y}", Flow.NEXT),
    Opcode(0xF00F, 0x8005, Kind.SUB, _C, "{x} -= {y}", Flow.NEXT),
    Opcode(0xF00F, 0x8006, Kind.SHR, _C, "{x} >>= {y}", Flow.NEXT),
    Opcode(0xF00F, 0x8007, Kind.SUBN, _C, "{x} =- {y}", Flow.NEXT),
    Opcode(0xF00F, 0x800E, Kind.SHL, _C, "{x} <<= {y}", Flow.NEXT),
    Opcode(0xF00F, 0x9000, Kind.SNE_XY, _C, "if {x} == {y} then", Flow.SKIP),
    Opcode(0xF000, 0xA000, Kind.LD_I, _C, "i := {target}", Flow.INDEX),
    Opcode(0xF000, 0xB000, Kind.JP_V, _C, "jump0 {target}", Flow.JUMP0),
    Opcode(0xF000, 0xC000, Kind.RND, _C, "{x} := random {nn}", Flow.NEXT),
    Opcode(0xF000, 0xD000, Kind.DRW, _C, "sprite {x} {y} {n}", Flow.NEXT),
    Opcode(0xF0FF, 0xE09E, Kind.SKP, _C, "if {x} -key then", Flow.SKIP),
    Opcode(0xF0FF, 0xE0A1, Kind.SKNP, _C, "if {x} key then", Flow.SKIP),
    Opcode(0xFFFF, 0xF000, Kind.LD_I_LONG, _X, "i := long {target}", Flow.INDEX),  # the address is the next word
    Opcode(0xFCFF, 0xF001, Kind.PLANE, _X, "plane {xn}", Flow.NEXT),  # Octo takes plane masks 0-3 only
    Opcode(0xFFFF, 0xF002, Kind.AUDIO, _X, "audio", Flow.NEXT),
    Opcode(0xF0FF, 0xF007, Kind.LD_VX_DT, _C, "{x} := delay", Flow.NEXT),
    Opcode(0xF0FF, 0xF00A, Kind.LD_KEY, _C, "{x} := key", Flow.NEXT),
    Opcode(0xF0FF, 0xF015, Kind.LD_DT, _C, "delay := {x}", Flow.NEXT),
    Opcode(0xF0FF, 0xF018, Kind.LD_ST, _C, "buzzer := {x}", Flow.NEXT),
    Opcode(0xF0FF, 0xF01E, Kind.ADD_I, _C, "i += {x}", Flow.NEXT),
    Opcode(0xF0FF, 0xF029, Kind.LD_FONT, _C, "i := hex {x}", Flow.NEXT),
    Opcode(0xF0FF, 0xF030, Kind.LD_BIG_FONT, _S, "i := bighex {x}", Flow.NEXT),
    Opcode(0xF0FF, 0xF033, Kind.BCD, _C, "bcd {x}", Flow.NEXT),
    Opcode(0xF0FF, 0xF03A, Kind.PITCH, _X, "pitch := {x}", Flow.NEXT),
    Opcode(0xF0FF, 0xF055, Kind.STORE, _C, "save {x}", Flow.NEXT),
    Opcode(0xF0FF, 0xF065, Kind.LOAD, _C, "load {x}", Flow.NEXT),
    Opcode(0xF0FF, 0xF075, Kind.SAVE_FLAGS, _S, "saveflags {x}", Flow.NEXT),  # 16 flags, as Octo
    Opcode(0xF0FF, 0xF085, Kind.LOAD_FLAGS, _S, "loadflags {x}", Flow.NEXT),
)


LEVELS = {_C: 0, _S: 1, _X: 2}  # each platform runs the opcodes of its own level and below


def lookup(word: int) -> Optional[Opcode]:
    """The first row of `OPCODES` that `word` (0..0xFFFF) matches, or None."""
    return next((row for row in OPCODES if word & row.mask == row.pattern), None)


def kind_on(word: int, platform: str) -> Kind:
    """The kind a `platform` machine runs `word` as: NOP for a word that platform does not know
    (no row, a row without a kind, or a row of a later platform)."""
    row = lookup(word)
    if row is None or row.kind is None or LEVELS[row.platform] > LEVELS[platform]:
        return Kind.NOP
    return row.kind
