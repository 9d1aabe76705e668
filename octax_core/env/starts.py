"""Where episodes start: the boot image past the game's start-up, and the no-op start states.

Both are made once, at `make`, on the host; a reset then only picks a start and reseeds it.

* The start-up (key presses past title screens and menus, `GameSpec.startup`) runs after boot;
  its end state is the template every episode starts from.
* With `noop_max` M > 0 (the ALE protocol: up to 30 no-op steps before the agent acts), the
  no-op starts are made too: `NOOP_VARIANTS` copies of the template, each with its own CXNN
  seed, take M no-op steps, and the state after each step is kept, a pool of (M + 1) x
  `NOOP_VARIANTS` start states. A reset draws one uniformly, so its no-op count is uniform in
  0..M, and gives it a fresh CXNN seed from the reset key.

Why a pool: running the no-ops inside `reset` costs M env steps, and under `vmap` a loop whose
trip count differs per env runs the batch's longest, so every reset (and, with autoreset, every
step) paid M steps for every env. Drawing from the pool is a gather, whatever M is. What it
gives up: the random draws made during the no-op steps are the pool's, so two episodes that
draw the same entry agree up to their first action; from then on each follows its own seed.
"""

from __future__ import annotations

import functools
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.keypad import keys_to_mask
from octax_core.emulator.machine import Machine
from octax_core.emulator.rom import Rom
from octax_core.emulator.state import MachineState, seed_rng

NOOP_VARIANTS = 4  # independent no-op runs per count: (M + 1) x 4 distinct starts
_POOL_SEED = 0  # the pool's own CXNN seeds derive from this, never from an episode's key


def boot(machine: Machine, rom: Rom, startup: tuple[tuple[int, int], ...]) -> MachineState:
    """Boots `rom` and runs the start-up, (key mask, frames) after (key mask, frames).

    Returns the template state with host numpy leaves (its CXNN seed is replaced at reset).
    """
    state = machine.boot(rom, jax.random.key(_POOL_SEED))
    run = _frames_runner(machine)
    for mask, frames in startup:
        state = run(state, keys_to_mask(mask), jnp.int32(frames))
    return jax.tree.map(np.asarray, state)


@functools.lru_cache(maxsize=None)
def _frames_runner(machine: Machine):
    """`machine.run_frames` with the frame count traced: one compile per machine config."""
    return jax.jit(lambda state, mask, frames: machine.run_frames(state, mask, frames),
                   compiler_options=machine.compiler_options)


def noop_pool(template: MachineState, noop_step: Callable[[MachineState], MachineState],
              noop_max: int, variants: int = NOOP_VARIANTS) -> MachineState:
    """The start states: the template after 0..noop_max no-op steps, `variants` runs each.

    Args:
        template: the state after start-up (host arrays).
        noop_step: one env step with no key held, for a batch of states (jitted by the caller).
        noop_max: the largest no-op count, >= 0.
        variants: runs per count, each from its own CXNN seed (1 when noop_max is 0: every
            count-0 start is the template).

    Returns:
        A `MachineState` whose leaves have a leading axis of (noop_max + 1) * variants, host
        numpy arrays, ordered by no-op count.
    """
    if noop_max == 0:
        return jax.tree.map(lambda leaf: leaf[None], template)
    seeds = jax.vmap(lambda k: seed_rng(jax.random.fold_in(jax.random.key(_POOL_SEED), k)))(jnp.arange(variants))
    states = jax.tree.map(lambda leaf: jnp.broadcast_to(leaf, (variants, *leaf.shape)), template)
    states = states.replace(rng=seeds)
    kept = [jax.device_get(states)]
    for _ in range(noop_max):
        states = noop_step(states)
        kept.append(jax.device_get(states))
    return jax.tree.map(lambda *leaves: np.concatenate(leaves), *kept)


def draw(pool: MachineState, key: jax.Array) -> MachineState:
    """A reset's machine: a uniform draw from `pool` (`noop_pool`), reseeded from `key`.

    A pool of one (no no-op starts) needs no draw: the template is used as it is.
    """
    rng_key, start_key = jax.random.split(key)
    count = jax.tree.leaves(pool)[0].shape[0]
    if count == 1:
        machine = jax.tree.map(lambda leaf: jnp.asarray(leaf[0]), pool)
    else:
        index = jax.random.randint(start_key, (), 0, count)
        machine = jax.tree.map(lambda leaf: jnp.asarray(leaf)[index], pool)
    return machine.replace(rng=seed_rng(rng_key))
