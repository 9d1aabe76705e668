"""The frame loop: every way of running a machine for some 60 Hz frames goes through here.

A frame is up to `instructions_per_frame` instructions (fewer when a DXYN ends it under the
display-wait quirk, or 00FD ends the program), then the timer tick, and, when asked for, the
picture recorded. One loop serves every path: plain lockstep runs, exact idle skipping
(`octax_core.emulator.idle`), recorded screens, halted machines (an env's ended episodes), and
the three platforms (`cpu.execute` is the one executor).

Each machine keeps its own frame clock (`Clock`). Without idle skipping a loop step is a whole
frame of every machine, in lockstep. With it, a step is a chunk of instructions, after which
`idle.detect` may shorten the frame of a machine that provably spins; a machine whose frame ends
ticks its timers, records its screen and starts its next frame while the others are still busy,
so a call of F frames costs the busiest machine's total over its F frames. Under `vmap` the loop
runs while any machine still has work; machines that are done run STALL (nothing changes) rather
than being selected over, so no memory-sized select is paid per instruction:
`jax.custom_batching.custom_vmap` gives the batched loop that shape.
"""

from __future__ import annotations

import functools
from typing import NamedTuple, Optional

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator import cpu, idle
from octax_core.emulator.gate import _batch, when_any
from octax_core.emulator.opcodes import Kind
from octax_core.emulator.platforms import Platform
from octax_core.emulator.quirks import FIELDS, Quirks, lane_quirks
from octax_core.emulator.state import shown


class Clock(NamedTuple):
    """One machine's frame clock and cycle detector, carried through the loop from step to step."""

    frame: jax.Array  # () int32, frames ended in this call; `frames` when the machine is done
    count: jax.Array  # () int32, instructions run in the current frame
    target: jax.Array  # () int32, the frame ends when count reaches it: instructions_per_frame, or less
    detector: idle.Detector  # the cycle detector's state (empty arrays without idle skipping)
    screens: jax.Array  # (frames, *screen) uint32, the picture at each frame's end (or a dummy); rows
    #                     not reached yet hold the picture at the start, or at the exit after 00FD


class Loop(NamedTuple):
    """The static shape of one frame loop (hashable: `frame_runner` caches one program per loop)."""

    platform: Platform
    quirks: Quirks
    instructions_per_frame: int
    frames: int
    record_screens: bool
    skip_idle: bool
    chunk: int  # instructions per loop step: the whole frame without idle skipping
    # A mix of games (`Machine(profiles=...)`): (quirks, instructions per frame) per profile; each
    # machine runs the one its profile index picks, and `quirks` and `instructions_per_frame`
    # above are then unused (the largest instructions per frame sizes the chunks).
    profiles: tuple[tuple[Quirks, int], ...] = ()

    def lane(self, profile):
        """(quirks, instructions per frame) of the machine running `profile`: the loop's own for
        one profile; for a mix, what the profiles share as constants and the rest looked up."""
        if not self.profiles:
            return self.quirks, self.instructions_per_frame
        quirks = lane_quirks([q for q, _ in self.profiles], profile)
        speeds = [ipf for _, ipf in self.profiles]
        if len(set(speeds)) == 1:
            return quirks, speeds[0]
        return quirks, jnp.asarray(speeds, jnp.int32)[profile]


def _start(loop: Loop, state, halted, profile) -> Clock:
    """The clock of a machine at the call's start; a halted machine, or one after 00FD, is done."""
    instructions_per_frame = loop.lane(profile)[1]
    still = halted | state.exited
    zero = jnp.zeros_like(state.pc, dtype=jnp.int32)
    picture = shown(state)
    if loop.record_screens:
        # Every row starts as the picture now: what a machine that runs no frame (halted, exited)
        # shows in all of them. The frames that do run overwrite theirs.
        screens = jnp.broadcast_to(picture[None], (loop.frames, *picture.shape))
    else:
        screens = jnp.zeros((1, *picture.shape), picture.dtype)  # a dummy: nothing is recorded
    return Clock(frame=jnp.where(still, loop.frames, 0).astype(jnp.int32), count=zero,
                 target=zero + instructions_per_frame, detector=idle.start(state, loop.skip_idle),
                 screens=screens)


def _chunk(loop: Loop, keys, state, clock: Clock, profile):
    """Up to `loop.chunk` instructions of one machine: each runs while its frame goes on (count
    below the target, no display wait or exit yet), else it is a STALL. Returns the state, the
    count, whether the frame is over, and whether any instruction wrote memory or the screen."""
    frame_going = clock.frame < loop.frames
    quirks, instructions_per_frame = loop.lane(profile)
    # Without skipping a chunk is the frame, and the count cannot reach the target early, unless
    # the machines of a mix run frames of different lengths.
    counted = loop.skip_idle or not isinstance(instructions_per_frame, int)

    def instruction(carry, _):
        state, count, over, dirty = carry
        stalled = over | ~frame_going
        if counted:
            stalled = stalled | (count >= clock.target)
        state, kind = _execute(loop.platform, quirks, state, keys, stalled)
        count = count + jnp.where(stalled, 0, 1)
        # The VIP's DXYN waits for the next vertical blank: the frame is over.
        if quirks.display_wait is True:
            over = over | (kind == Kind.DRW)
        elif quirks.display_wait is not False:  # a mix of profiles: each machine's own answer
            over = over | (quirks.display_wait & (kind == Kind.DRW))
        if state.extension is not None:  # 00FD: this frame ends here; later ones do nothing
            over = over | state.extension.exited
        if loop.skip_idle:
            dirty = dirty | ~jnp.asarray(idle.PURE)[kind]
        return (state, count, over, dirty), None

    no = jnp.zeros_like(clock.count, dtype=jnp.bool_)  # built from the state: batched / sharded like it
    carry = (state, clock.count, no, no)
    (state, count, over, dirty), _ = jax.lax.scan(instruction, carry, None, length=loop.chunk)
    return state, count, over, dirty


def _execute(platform: Platform, quirks: Quirks, state, keys, stalled):
    """`cpu.execute`, traced once per process for each platform and set of fixed quirks.

    Every program that runs a machine (an env's reset and step, a rollout, at any batch size)
    traces the same instruction, and under `vmap` batches it again; as a jitted call JAX keeps
    its jaxpr and the batched jaxpr, so the programs after the first trace only their own code.
    XLA inlines the call: the optimized program is the same, instruction for instruction, as
    with `cpu.execute` traced in place (docs/machine-log.md). A mix's quirks that differ per
    machine (traced bools, `lane_quirks`) are arguments of the call, not part of its key."""
    fixed = tuple((name, bool(value)) for name in FIELDS
                  if isinstance(value := getattr(quirks, name), (bool, np.bool_)))
    varying = {name: getattr(quirks, name) for name in FIELDS if name not in dict(fixed)}
    return _execute_once(platform, fixed, state, keys, stalled, varying)


@functools.partial(jax.jit, static_argnums=(0, 1))
def _execute_once(platform: Platform, fixed: tuple[tuple[str, bool], ...], state, keys, stalled, varying):
    return cpu.execute(platform, Quirks(**dict(fixed), **varying), state, keys, stalled)


def _step(loop: Loop, keys, profile, carry):
    """One loop step of one machine: a chunk of instructions, then (with idle skipping) the cycle
    check. Returns the state, the clock and whether the machine's frame has ended."""
    state, clock = carry
    running = clock.frame < loop.frames
    state, count, over, dirty = _chunk(loop, keys, state, clock, profile)
    if not loop.skip_idle:
        return state, clock._replace(count=count), running
    target, detector = idle.detect(clock.detector, state, count, dirty, clock.target, loop.lane(profile)[1])
    clock = clock._replace(count=count, target=target, detector=detector)
    return state, clock, running & (over | (count >= target))


def _end_frame(loop: Loop, profile, ended, state, clock: Clock):
    """Where `ended`: the timer tick, the picture recorded, and a fresh clock for the next frame.
    `state` comes without its memory, which no frame's end touches, so that a `lax.cond` around
    this never copies it."""
    state = cpu.tick_timers(state, ended)
    screens = clock.screens
    exiting = ended & state.exited
    if loop.record_screens:
        at = jnp.minimum(clock.frame, loop.frames - 1)
        old = jax.lax.dynamic_index_in_dim(screens, at, keepdims=False)
        picture = shown(state)
        screens = jax.lax.dynamic_update_index_in_dim(screens, jnp.where(ended, picture, old), at, 0)
        if state.extension is not None:  # after 00FD the frames left show the last picture
            screens = when_any(exiting, _fill_after, screens, (picture, at, exiting))
    frame = jnp.where(ended, clock.frame + 1, clock.frame)
    frame = jnp.where(exiting, loop.frames, frame)  # after 00FD the frames left do nothing
    return state, Clock(
        frame=frame,
        count=jnp.where(ended, 0, clock.count),
        target=jnp.where(ended, loop.lane(profile)[1], clock.target),
        detector=idle.restart(clock.detector, state, ended) if loop.skip_idle else clock.detector,
        screens=screens,
    )


def _loop_body(loop: Loop, batched: bool, keys, profile, carry):
    """A step for every machine, then the frames' ends. With idle skipping most steps end no
    frame, so the ends run inside a `lax.cond` (one branch on a flag); without, every step
    ends every running machine's frame."""
    step = functools.partial(_step, loop)
    end = functools.partial(_end_frame, loop)
    if batched:
        step, end = jax.vmap(step), jax.vmap(end)
    end = functools.partial(end, profile)
    state, clock, ended = step(keys, profile, carry)
    light = state.replace(memory=None)
    if loop.skip_idle:
        light, clock = jax.lax.cond(jnp.any(ended), end, lambda e, s, c: (s, c), ended, light, clock)
    else:
        light, clock = end(ended, light, clock)
    return light.replace(memory=state.memory), clock


def _fill_after(screens, inputs):
    """`when_any`'s work at a 00FD: the rows after `at` get the picture, where `exiting`."""
    picture, at, exiting = inputs
    rows = jnp.arange(screens.shape[0]).reshape((-1,) + (1,) * picture.ndim)
    return jnp.where((rows > at) & exiting, picture[None], screens)


def _finish(state, clock: Clock, record_screens: bool):
    """The state, and the pictures (None unless recorded). They come straight out of the loop, rows
    not run filled already (`_start`, `_fill_after`): a select here, after the loop, would be fused
    into the observation's unpack and its picture (a lores screen doubled, a hires choice)
    recomputed for every pixel, which costs more than the rest of the observation (measured:
    docs/machine-log.md)."""
    return state, (clock.screens if record_screens else None)


@functools.lru_cache(maxsize=None)
def frame_runner(platform: Platform, quirks: Quirks, instructions_per_frame: int, frames: int,
                 record_screens: bool, skip_idle: bool, chunk: Optional[int] = None,
                 profiles: tuple[tuple[Quirks, int], ...] = ()):
    """`run(state, keys, halted, profile) -> (state, screens or None)`: `frames` frames of one
    machine; batch it with `jax.vmap` (its batching rule is the lockstep loop over every machine,
    see the module docstring). A `halted` machine (bool), like one after 00FD, does nothing this
    call: its state comes back unchanged. `skip_idle` skips idle instructions (`idle`), in chunks
    of `chunk` instructions (`idle.chunk_size` by default). With `profiles` (a mix of games, each
    machine its own quirks and speed), `profile` (int32) is the machine's index into them and
    `instructions_per_frame` their largest; without, `profile` is unused."""
    if skip_idle:
        chunk = idle.chunk_size(instructions_per_frame) if chunk is None else min(chunk, instructions_per_frame)
    else:
        chunk = instructions_per_frame
    loop = Loop(platform, quirks, instructions_per_frame, frames, record_screens, skip_idle, chunk, profiles)

    @jax.custom_batching.custom_vmap
    def run(state, keys, halted, profile):
        carry = (state, _start(loop, state, halted, profile))
        state, clock = jax.lax.while_loop(lambda c: c[1].frame < frames,
                                          functools.partial(_loop_body, loop, False, keys, profile), carry)
        return _finish(state, clock, record_screens)

    @run.def_vmap
    def run_batched(axis_size, in_batched, state, keys, halted, profile):
        state, keys, halted, profile = (_batch(tree, batched, axis_size)
                                        for tree, batched in zip((state, keys, halted, profile), in_batched))
        carry = (state, jax.vmap(functools.partial(_start, loop))(state, halted, profile))
        state, clock = jax.lax.while_loop(lambda c: jnp.any(c[1].frame < frames),
                                          functools.partial(_loop_body, loop, True, keys, profile), carry)
        out = jax.vmap(lambda s, c: _finish(s, c, record_screens))(state, clock)
        return out, jax.tree.map(lambda _: True, out)

    return run
