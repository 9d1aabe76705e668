"""Control flow: jumps, calls, returns and the register-compare skips."""

from __future__ import annotations

from octax_core.emulator.ops import Context, Effect, next_pc
from octax_core.emulator.quirks import choose


def op_00ee(c: Context) -> Effect:
    """RET: pop the return address."""
    return Effect(pc=c.stack_top, sp=(c.sp - 1) & 0xF)


def op_1nnn(c: Context) -> Effect:
    """JP nnn."""
    return Effect(pc=c.nnn)


def op_2nnn(c: Context) -> Effect:
    """CALL nnn: push pc + 2."""
    return Effect(pc=c.nnn, sp=(c.sp + 1) & 0xF, push=c.pc + 2)


def op_3xnn(c: Context) -> Effect:
    """SE Vx, nn: skip if equal."""
    return Effect(pc=next_pc(c, c.vx == c.nn))


def op_4xnn(c: Context) -> Effect:
    """SNE Vx, nn: skip if not equal."""
    return Effect(pc=next_pc(c, c.vx != c.nn))


def op_5xy0(c: Context) -> Effect:
    """SE Vx, Vy: skip if equal."""
    return Effect(pc=next_pc(c, c.vx == c.vy))


def op_9xy0(c: Context) -> Effect:
    """SNE Vx, Vy: skip if not equal."""
    return Effect(pc=next_pc(c, c.vx != c.vy))


def op_bnnn(c: Context) -> Effect:
    """JP V0, nnn (or JP Vx, xnn with jump_uses_vx)."""
    return Effect(pc=c.nnn + choose(c.quirks.jump_uses_vx, c.vx, c.v0))


def op_stall(c: Context) -> Effect:
    """Not an opcode: the frame has ended (display wait), so nothing moves, pc included."""
    return Effect(pc=c.pc)
