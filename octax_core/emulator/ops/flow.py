"""Control flow: jumps, calls, returns and the register-compare skips."""

from __future__ import annotations

from octax_core.emulator.ops import Context, next_pc


def op_00ee(c: Context) -> dict:
    """RET: pop the return address."""
    return {"pc": c.stack_top, "sp": (c.sp - 1) & 0xF}


def op_1nnn(c: Context) -> dict:
    """JP nnn."""
    return {"pc": c.nnn}


def op_2nnn(c: Context) -> dict:
    """CALL nnn: push pc + 2."""
    return {"pc": c.nnn, "sp": (c.sp + 1) & 0xF, "push": c.pc + 2}


def op_3xnn(c: Context) -> dict:
    """SE Vx, nn: skip if equal."""
    return {"pc": next_pc(c, c.vx == c.nn)}


def op_4xnn(c: Context) -> dict:
    """SNE Vx, nn: skip if not equal."""
    return {"pc": next_pc(c, c.vx != c.nn)}


def op_5xy0(c: Context) -> dict:
    """SE Vx, Vy: skip if equal."""
    return {"pc": next_pc(c, c.vx == c.vy)}


def op_9xy0(c: Context) -> dict:
    """SNE Vx, Vy: skip if not equal."""
    return {"pc": next_pc(c, c.vx != c.vy)}


def op_bnnn(c: Context) -> dict:
    """JP V0, nnn (or JP Vx, xnn with jump_uses_vx)."""
    return {"pc": c.nnn + (c.vx if c.quirks.jump_uses_vx else c.v0)}


def op_stall(c: Context) -> dict:
    """Not an opcode: the frame has ended (display wait), so nothing moves, pc included."""
    return {"pc": c.pc}
