"""Exact idle skipping: each machine runs only the instructions that change what comes next.

A CHIP-8 program that has finished a frame's work spins until the next 60 Hz tick: on the delay
timer (`loop vf := delay if vf != 0 then again`), on a key it does not have, in FX0A, or on a
jump to itself. Within one frame the keys and the timers are fixed, so a spin is an exact cycle:
once the registers (everything but memory and the screen) come back to a value they had, with no
memory or screen write in between, every later instruction of the frame repeats that cycle. The
frame's end is then known without running it: after `count` instructions with a cycle of
`period`, the state at the frame's end is the state `(instructions_per_frame - count) % period`
instructions on. So a machine runs those few and ends its frame: the same pc, registers, memory
and screen as running every instruction, bit for bit.

The detection is Brent's cycle finding on the register vector (`registers`), restarted at every
instruction that writes memory or the screen (`PURE` says which do not) and at every frame's
start. It covers any loop that leaves memory and the screen alone, whatever its shape: timer
waits, key polls, FX0A, jump-to-self, `loop again` with a counter that wraps are all cycles. A loop that
draws (flickering) or stores, or one that calls CXNN (the random state moves on), is not, and
runs in full.

This module is the detector (`Detector`, `start`, `detect`, `restart`) and its constants; the
frame loop that runs the chunks and gives each machine its own frame clock is
`octax_core.emulator.frame`, the same loop that runs every frame without skipping.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.opcodes import Kind

# Kinds that write neither memory nor the screen (registers, timers, flags, I, pc and the stack
# only). Anything not listed (DXYN, 00E0, FX33, FX55, 5XY2, scrolls, 00FE/00FF, 00FD, and any
# kind added later) restarts the cycle detection.
PURE_KINDS = frozenset({
    Kind.NOP, Kind.STALL, Kind.RET, Kind.JP, Kind.CALL, Kind.SE_NN, Kind.SNE_NN, Kind.SE_XY, Kind.LD_NN,
    Kind.ADD_NN, Kind.LD_XY, Kind.OR, Kind.AND, Kind.XOR, Kind.ADD_XY, Kind.SUB, Kind.SHR, Kind.SUBN, Kind.SHL,
    Kind.SNE_XY, Kind.LD_I, Kind.JP_V, Kind.RND, Kind.SKP, Kind.SKNP, Kind.LD_VX_DT, Kind.LD_KEY, Kind.LD_DT,
    Kind.LD_ST, Kind.ADD_I, Kind.LD_FONT, Kind.LOAD, Kind.LD_BIG_FONT, Kind.SAVE_FLAGS, Kind.LOAD_FLAGS,
    Kind.LOAD_RANGE, Kind.LD_I_LONG, Kind.PLANE, Kind.AUDIO, Kind.PITCH,
})
PURE = np.array([Kind(k) in PURE_KINDS for k in range(len(Kind))], np.bool_)


def registers(state) -> jax.Array:
    """(R,) uint32: every field of the state but memory and the screen (the extension's
    included), in one vector."""
    extension = None if state.extension is None else state.extension.replace(grid=None)
    leaves = jax.tree.leaves(state.replace(memory=None, screen=None, extension=extension))
    return jnp.concatenate([jnp.ravel(leaf).astype(jnp.uint32) for leaf in leaves])


class Detector(NamedTuple):
    """Brent's cycle finding on one machine's registers, carried from chunk to chunk."""

    snapshot: jax.Array  # (R,) uint32, Brent's tortoise: the registers the cycle must come back to
    snapshot_count: jax.Array  # () int32, the frame's instruction count when the snapshot was taken
    power: jax.Array  # () int32, Brent's power of two: the tortoise moves when lam reaches it
    lam: jax.Array  # () int32, chunks since the tortoise last moved
    found: jax.Array  # () bool, a cycle is known: the frame's target is set


def start(state, enabled: bool = True) -> Detector:
    """A detector at a frame's start; empty arrays when idle skipping is off (nothing to carry)."""
    zero = jnp.zeros_like(state.pc, dtype=jnp.int32)
    if not enabled:
        return Detector(jnp.zeros((0,), jnp.uint32), zero, zero, zero, zero > 0)
    return Detector(snapshot=registers(state), snapshot_count=zero, power=zero + 1, lam=zero, found=zero > 0)


def restart(detector: Detector, state, ended) -> Detector:
    """Where `ended`: a fresh detector for the next frame (its first snapshot: the ticked registers)."""
    fresh = start(state)
    return jax.tree.map(lambda new, old: jnp.where(ended, new, old), fresh, detector)


def detect(detector: Detector, state, count, dirty, target, instructions_per_frame: int):
    """Brent at a chunk's end: any write in the chunk restarts the detection from here; a repeat
    of the registers means `period` instructions ago they were these, memory and screen too, so
    the frame ends after `(instructions_per_frame - count) % period` more. Returns the frame's
    (possibly shortened) target and the detector."""
    regs = registers(state)
    lam = detector.lam + 1
    repeat = ~dirty & ~detector.found & jnp.all(regs == detector.snapshot)
    period = jnp.maximum(count - detector.snapshot_count, 1)
    target = jnp.where(repeat, count + (instructions_per_frame - count) % period, target)
    moves = dirty | (lam == detector.power)
    return target, Detector(
        snapshot=jnp.where(moves, regs, detector.snapshot),
        snapshot_count=jnp.where(moves, count, detector.snapshot_count),
        power=jnp.where(dirty, 1, jnp.where(moves, detector.power * 2, detector.power)),
        lam=jnp.where(moves, 0, lam),
        found=detector.found | repeat,
    )


# Instructions per loop step: the clock's bookkeeping is paid once per chunk. 12 is a multiple of
# the periods of the usual spins (1: jump to self, 2: a key poll, 3: a timer wait, 4, 6), so a spin
# repeats from one chunk's end to the next and is found two chunks after it starts; a smaller
# chunk pays the bookkeeping more often (12 against 8, measured: docs/machine-log.md).
CHUNK = 12


def chunk_size(instructions_per_frame: int) -> int:
    """CHUNK, unless a busy frame would waste more than 3% of its slots in its last, partial chunk
    (a frame of 30 would run 3 chunks of 12: 36 slots): then the largest divisor of the frame
    length from 5 to 16, if there is one (30 -> 15, 100 -> 10). Larger chunks pay the clock less
    often, so the largest divisor, not the smallest (measured: docs/machine-log.md)."""
    slots = -(-instructions_per_frame // CHUNK) * CHUNK
    if slots - instructions_per_frame <= 0.03 * instructions_per_frame:
        return min(CHUNK, instructions_per_frame)
    divisors = [d for d in range(5, 17) if instructions_per_frame % d == 0]
    return max(divisors) if divisors else min(CHUNK, instructions_per_frame)


# Below this many instructions per frame a frame holds too little to skip for the clock to pay
# (the games measured on each side of it: docs/machine-log.md), and `Machine` runs the plain
# lockstep loop, whose results are the same.
SKIP_FROM = 25
