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

Each machine keeps its own frame clock (`Clock`): a machine whose frame ends ticks its timers,
records its screen and starts its next frame while the others are still busy, so a call of F
frames costs the busiest machine's total over its F frames, not the sum of each frame's busiest.
Under `vmap` the loop runs while any machine still has work; machines that are done run STALL
(nothing changes) rather than being selected over, so no 4 KiB (or 64 KiB) memory select is
paid per instruction: `jax.custom_batching.custom_vmap` gives the batched loop that shape.
"""

from __future__ import annotations

import functools
from typing import Callable, NamedTuple, Optional

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator import cpu, cpu_extended
from octax_core.emulator.opcodes import Kind
from octax_core.emulator.platforms import Platform
from octax_core.emulator.quirks import Quirks

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

# The fields a cycle must repeat: everything but the memory and the screen, which no pure
# instruction changes.
_NOT_REGISTERS = ("memory", "screen")

# execute(state, keys, stalled) -> (state, int32 Kind): one instruction of the platform.
Execute = Callable[..., tuple]


def _executor(platform: Platform, quirks: Quirks) -> Execute:
    if platform.extended:
        return functools.partial(cpu_extended.execute, platform, quirks)
    return functools.partial(cpu.execute, quirks)


def registers(state) -> jax.Array:
    """(R,) uint32: every field of the state but memory and the screen, in one vector."""
    parts = [jnp.ravel(getattr(state, name)).astype(jnp.uint32)
             for name in state.__dataclass_fields__ if name not in _NOT_REGISTERS
             and getattr(state, name) is not None]
    return jnp.concatenate(parts)


class Clock(NamedTuple):
    """One machine's frame clock and cycle detector, carried through the loop from chunk to chunk."""

    frame: jax.Array  # () int32, frames ended in this call; `frames` when the machine is done
    count: jax.Array  # () int32, instructions run in the current frame
    target: jax.Array  # () int32, the frame ends when count reaches it: instructions_per_frame, or less
    snapshot: jax.Array  # (R,) uint32, Brent's tortoise: the registers the cycle must come back to
    snapshot_count: jax.Array  # () int32, the count at which the snapshot was taken
    power: jax.Array  # () int32, Brent's power of two: the tortoise moves when lam reaches it
    lam: jax.Array  # () int32, chunks since the tortoise last moved
    found: jax.Array  # () bool, a cycle is known: the target is set
    recorded: jax.Array  # () int32, screens recorded (after an exit, the rest repeat the last)
    screens: jax.Array  # (frames, *screen) uint32, the screen at each frame's end (or a dummy)


def _start(state, instructions_per_frame: int, frames: int, record_screens: bool, halted) -> Clock:
    """The clock of a machine at the call's start; a halted machine, or one after 00FD, is done."""
    still = halted if state.exited is None else halted | state.exited
    zero = jnp.zeros_like(state.pc, dtype=jnp.int32)
    screens = jnp.zeros((frames if record_screens else 1, *state.screen.shape), state.screen.dtype)
    return Clock(frame=jnp.where(still, frames, 0).astype(jnp.int32), count=zero, target=zero + instructions_per_frame,
                 snapshot=registers(state), snapshot_count=zero, power=zero + 1, lam=zero, found=zero > 0,
                 recorded=zero, screens=screens)


def _chunk(execute: Execute, chunk: int, frames: int, display_wait: bool, keys, state, clock: Clock):
    """Up to `chunk` instructions of one machine: each runs while its frame goes on (count below
    the target, no display wait or exit yet), else it is a STALL. Returns the state, the count,
    whether the frame is over, and whether any instruction wrote memory or the screen."""
    frame_going = clock.frame < frames

    def instruction(carry, _):
        state, count, over, dirty = carry
        stalled = over | (count >= clock.target) | ~frame_going
        state, kind = execute(state, keys, stalled)
        count = count + jnp.where(stalled, 0, 1)
        if display_wait:  # the VIP's DXYN waits for the next vertical blank: the frame is over
            over = over | (kind == Kind.DRW)
        if state.exited is not None:  # 00FD: this frame ends here; later ones do nothing
            over = over | state.exited
        return (state, count, over, dirty | ~jnp.asarray(PURE)[kind]), None

    no = jnp.zeros_like(clock.count, dtype=jnp.bool_)  # built from the state: batched / sharded like it
    carry = (state, clock.count, no, no)
    (state, count, over, dirty), _ = jax.lax.scan(instruction, carry, None, length=chunk)
    return state, count, over, dirty


def _step(execute: Execute, instructions_per_frame: int, chunk: int, frames: int, display_wait: bool, keys, carry):
    """One loop step of one machine: a chunk of instructions, then the cycle check. Returns the
    state, the clock and whether the machine's frame has ended (`_end_frame` then runs)."""
    state, clock = carry
    running = clock.frame < frames
    state, count, over, dirty = _chunk(execute, chunk, frames, display_wait, keys, state, clock)

    # Brent on the registers at chunk ends; any write in the chunk restarts it from here. A
    # repeat means: `period` instructions ago the registers were these, memory and screen too.
    regs = registers(state)
    lam = clock.lam + 1
    repeat = ~dirty & ~clock.found & jnp.all(regs == clock.snapshot)
    period = jnp.maximum(count - clock.snapshot_count, 1)
    target = jnp.where(repeat, count + (instructions_per_frame - count) % period, clock.target)
    moves = dirty | (lam == clock.power)
    clock = clock._replace(
        count=count, target=target, found=clock.found | repeat,
        snapshot=jnp.where(moves, regs, clock.snapshot),
        snapshot_count=jnp.where(moves, count, clock.snapshot_count),
        power=jnp.where(dirty, 1, jnp.where(moves, clock.power * 2, clock.power)),
        lam=jnp.where(moves, 0, lam),
    )
    return state, clock, running & (over | (count >= target))


def _end_frame(instructions_per_frame: int, frames: int, record_screens: bool, ended, state, clock: Clock):
    """Where `ended`: the timer tick, the screen recorded, and a fresh clock for the next frame
    (whose first snapshot is the ticked registers). `state` comes without its memory, which no
    frame's end touches, so that a `lax.cond` around this never copies it."""
    tick = lambda timer: jnp.where(ended & (timer > 0), timer - 1, timer).astype(timer.dtype)
    state = state.replace(delay_timer=tick(state.delay_timer), sound_timer=tick(state.sound_timer))
    screens = clock.screens
    if record_screens:
        at = jnp.minimum(clock.frame, frames - 1)
        old = jax.lax.dynamic_index_in_dim(screens, at, keepdims=False)
        screens = jax.lax.dynamic_update_index_in_dim(screens, jnp.where(ended, state.screen, old), at, 0)
    frame = jnp.where(ended, clock.frame + 1, clock.frame)
    if state.exited is not None:  # after 00FD the frames left do nothing, their timers included
        frame = jnp.where(ended & state.exited, frames, frame)
    return state, Clock(
        frame=frame,
        count=jnp.where(ended, 0, clock.count),
        target=jnp.where(ended, instructions_per_frame, clock.target),
        snapshot=jnp.where(ended, registers(state), clock.snapshot),
        snapshot_count=jnp.where(ended, 0, clock.snapshot_count),
        power=jnp.where(ended, 1, clock.power),
        lam=jnp.where(ended, 0, clock.lam),
        found=~ended & clock.found,
        recorded=jnp.where(ended, clock.frame + 1, clock.recorded),
        screens=screens,
    )


def _loop_body(step, end_frame, batched: bool, keys, carry):
    """A chunk for every machine, then the frames' ends, inside a `lax.cond`: most chunks end no
    frame, and then the cond costs one branch on a flag."""
    if batched:
        state, clock, ended = jax.vmap(step)(keys, carry)
    else:
        state, clock, ended = step(keys, carry)
    light = state.replace(memory=None)
    end = jax.vmap(end_frame) if batched else end_frame
    light, clock = jax.lax.cond(jnp.any(ended), end, lambda e, s, c: (s, c), ended, light, clock)
    return light.replace(memory=state.memory), clock


def _finish(state, clock: Clock, record_screens: bool):
    """The state, and the screens: frames after an exit (or all, for a still machine) show the last one."""
    if not record_screens:
        return state, None
    rows = jnp.arange(clock.screens.shape[0]).reshape((-1,) + (1,) * state.screen.ndim)
    return state, jnp.where(rows < clock.recorded, clock.screens, state.screen[None])


# Instructions per loop step: the clock's bookkeeping is paid once per chunk. 12 is a multiple of
# the periods of the usual spins (1: jump to self, 2: a key poll, 3: a timer wait, 4, 6), so a spin
# repeats from one chunk's end to the next and is found two chunks after it starts; measured on
# the archive's >= 200 ipf games at N = 64, 12 gave 3.6x where 8 gave 3.0x (docs/speed.md).
CHUNK = 12


def chunk_size(instructions_per_frame: int) -> int:
    """CHUNK, unless a busy frame would waste more than 3% of its slots in its last, partial chunk
    (a frame of 30 would run 3 chunks of 12: 36 slots): then the largest divisor of the frame
    length from 5 to 16, if there is one (30 -> 15, 100 -> 10). Larger chunks pay the clock less
    often: at 30 instructions a frame, 15 measured 1.02x and 6 0.93x on a busy game at N = 512."""
    slots = -(-instructions_per_frame // CHUNK) * CHUNK
    if slots - instructions_per_frame <= 0.03 * instructions_per_frame:
        return min(CHUNK, instructions_per_frame)
    divisors = [d for d in range(5, 17) if instructions_per_frame % d == 0]
    return max(divisors) if divisors else min(CHUNK, instructions_per_frame)


# Below this many instructions per frame a frame holds too little to skip for the clock to pay
# (Pong at 11: 0.92x, Carbon8 at 15: 0.84x, SuperPong at 30: 1.05x), and `Machine` runs the
# plain lockstep loop, whose results are the same.
SKIP_FROM = 25


@functools.lru_cache(maxsize=None)
def frame_runner(platform: Platform, quirks: Quirks, instructions_per_frame: int, frames: int,
                 record_screens: bool, chunk: Optional[int] = None):
    """`run(state, keys, halted) -> (state, screens or None)`: `frames` frames of one machine,
    skipping idle instructions; batch it with `jax.vmap` (its batching rule is the lockstep loop
    over every machine, see the module docstring). A `halted` machine (bool), like one after
    00FD, does nothing this call: its state comes back unchanged."""
    chunk = chunk_size(instructions_per_frame) if chunk is None else min(chunk, instructions_per_frame)
    step = functools.partial(_step, _executor(platform, quirks), instructions_per_frame, chunk, frames,
                             quirks.display_wait)
    end_frame = functools.partial(_end_frame, instructions_per_frame, frames, record_screens)

    @jax.custom_batching.custom_vmap
    def run(state, keys, halted):
        carry = (state, _start(state, instructions_per_frame, frames, record_screens, halted))
        state, clock = jax.lax.while_loop(lambda c: c[1].frame < frames,
                                          functools.partial(_loop_body, step, end_frame, False, keys), carry)
        return _finish(state, clock, record_screens)

    @run.def_vmap
    def run_batched(axis_size, in_batched, state, keys, halted):
        state, keys, halted = (_broadcast(tree, batched, axis_size)
                               for tree, batched in zip((state, keys, halted), in_batched))
        start = functools.partial(_start, instructions_per_frame=instructions_per_frame, frames=frames,
                                  record_screens=record_screens)
        carry = (state, jax.vmap(lambda s, h: start(s, halted=h))(state, halted))
        state, clock = jax.lax.while_loop(lambda c: jnp.any(c[1].frame < frames),
                                          functools.partial(_loop_body, step, end_frame, True, keys), carry)
        out = jax.vmap(lambda s, c: _finish(s, c, record_screens))(state, clock)
        return out, jax.tree.map(lambda _: True, out)

    return run


def _broadcast(tree, batched, axis_size: int):
    """Gives every unbatched leaf of `tree` a leading axis of `axis_size`."""
    return jax.tree.map(lambda leaf, b: leaf if b else jnp.broadcast_to(leaf, (axis_size, *jnp.shape(leaf))),
                        tree, batched)
