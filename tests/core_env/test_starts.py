"""No-op starts and the one env loop: what a reset draws, and what it costs.

The Ticker test game counts frames in V1, so a reset's state says how many no-op steps it
started after: V1 = 3 (start-up) + 4 x (no-op steps).
"""

import dataclasses

import jax
import numpy as np
import pytest

import octax_core
from octax_core.env import starts
from ticker_game import STARTUP_FRAMES, TICKER, TICKER_ROM

FRAMES = 4
# The tests of a pool share one env (noop_max=5) and one batch of resets: one compiled reset.
NOOP_MAX, BATCH = 5, 4000


@pytest.fixture(scope="module")
def ticker_rom(tmp_path_factory):
    path = tmp_path_factory.mktemp("ticker") / "ticker.ch8"
    path.write_bytes(TICKER_ROM)
    return path


@pytest.fixture(scope="module")
def ticker(ticker_rom):
    """make() plus a jitted batched reset, built once per noop_max (and options)."""
    cache = {}

    def build(noop_max, **options):
        key = (noop_max, tuple(sorted(options.items())))
        if key not in cache:
            env, params = octax_core.make(TICKER, rom=ticker_rom, noop_max=noop_max, **options)
            cache[key] = env, params, jax.jit(jax.vmap(env.reset, in_axes=(0, None)))
        return cache[key]
    return build


@pytest.fixture(scope="module")
def starts_batch(ticker):
    """BATCH resets of the noop_max=5 env: its env, params, reset keys, observations and states."""
    env, params, reset = ticker(NOOP_MAX)
    keys = jax.random.split(jax.random.key(0), BATCH)
    return env, params, keys, *reset(keys, params)


def noop_counts(states) -> np.ndarray:
    return (np.asarray(states.machine.V[:, 1]).astype(int) - STARTUP_FRAMES) // FRAMES


def test_no_op_counts_are_uniform_over_0_to_noop_max(starts_batch):
    *_, states = starts_batch
    frames = np.asarray(states.machine.V[:, 1]).astype(int)
    assert set((frames - STARTUP_FRAMES) % FRAMES) == {0}  # whole steps only
    counts = np.bincount(noop_counts(states), minlength=NOOP_MAX + 1)
    assert len(counts) == NOOP_MAX + 1 and counts.min() > 0  # every count 0..5 drawn, none beyond
    expected = BATCH / (NOOP_MAX + 1)  # uniform: about 667 each
    assert counts.min() > expected * 0.8 and counts.max() < expected * 1.2


def test_noop_max_0_starts_every_episode_at_the_template(ticker):
    _, params, reset = ticker(0)
    _, states = reset(jax.random.split(jax.random.key(1), 64), params)
    assert set(noop_counts(states)) == {0}


def test_a_start_is_the_template_after_its_no_op_steps_with_a_fresh_seed(ticker, starts_batch):
    """The pool's entry for k no-op steps is the state that k real no-op steps reach, except
    its CXNN seed, which each episode draws from its reset key."""
    env, params, _, _, states = starts_batch
    alone, _, _ = ticker(0)
    step = jax.jit(alone.step_env)
    by_count = {}
    for i, k in enumerate(noop_counts(states)):
        by_count.setdefault(int(k), i)
    assert sorted(by_count) == list(range(NOOP_MAX + 1))
    _, walked = alone.reset(jax.random.key(3), params)
    for k in range(NOOP_MAX + 1):
        row = jax.tree.map(lambda x: x[by_count[k]], states.machine)
        for name in ("memory", "V", "I", "pc", "sp", "stack", "delay_timer", "sound_timer", "screen", "key_wait"):
            if name == "V":  # V5 holds the pool's last random draw, which the pool's seed decided
                np.testing.assert_array_equal(np.delete(row.V, 5), np.delete(walked.machine.V, 5))
            else:
                np.testing.assert_array_equal(getattr(row, name), getattr(walked.machine, name), err_msg=f"{name} after {k}")
        _, walked, *_ = step(jax.random.key(k), walked, 0, params)
    rngs = np.asarray(states.machine.rng)
    assert len(set(rngs.tolist())) == len(rngs)  # every episode its own seed


def test_the_same_key_gives_the_same_start_whatever_the_batch(starts_batch):
    env, params, keys, _, batch = starts_batch
    for i in (0, 1234, BATCH - 1):
        _, alone = env.reset(keys[i], params)
        for a, b in zip(jax.tree.leaves(alone), jax.tree.leaves(jax.tree.map(lambda x: x[i], batch))):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def _loops(jaxpr) -> list[str]:
    """The loop primitives of a jaxpr, nested ones included, outermost first."""
    found = []
    for eqn in jaxpr.eqns:
        if eqn.primitive.name in ("while", "scan"):
            found.append(eqn.primitive.name)
        for param in eqn.params.values():
            for sub in (param if isinstance(param, (list, tuple)) else [param]):
                inner = getattr(sub, "jaxpr", None)
                if inner is not None:
                    found += _loops(getattr(inner, "jaxpr", inner))
    return found


@pytest.mark.parametrize("noop_max", [0, 30])
def test_reset_and_autoreset_run_no_loop_whatever_noop_max(ticker, noop_max):
    """A reset is a draw and a reseed: no loop. An autoresetting step runs the frame loops (4
    frames of 11 instructions, each with its memory-write gate) and the autoreset's gate
    (`gate.when_any`: a loop of zero trips or one, no trip when no episode ended), never a no-op
    loop, however many no-ops a start may take."""
    env, params, _ = ticker(noop_max, autoreset=True)
    reset = jax.make_jaxpr(jax.vmap(env.reset, in_axes=(0, None)))(jax.random.split(jax.random.key(0), 2), params)
    assert _loops(reset.jaxpr) == []
    _, state = env.reset(jax.random.key(0), params)
    step = jax.make_jaxpr(env.step)(jax.random.key(1), state, 1, params)
    # the one frame loop (octax_core.emulator.frame): frames, instructions within a frame, and
    # each instruction's memory-write gate (zero trips or one); then the autoreset's gate
    assert _loops(step.jaxpr) == ["while", "scan", "while", "while"]


def test_the_skip_idle_step_runs_the_same_loops(ticker_rom):
    """From 25 instructions a frame skip_idle (the default) runs the same loops over instruction
    chunks. The step's loops do not depend on the starts (the test above), so this env has no
    no-op starts and no start-up: nothing of its 100-instruction machine is compiled, only traced."""
    env, params = octax_core.make(dataclasses.replace(TICKER, startup=()), rom=ticker_rom, autoreset=True,
                                  instructions_per_frame=100)
    assert env.machine.skip_idle and env.config.noop_max == 0
    _, state = env.reset(jax.random.key(0), params)
    step = jax.make_jaxpr(env.step)(jax.random.key(1), state, 1, params)
    assert _loops(step.jaxpr) == ["while", "scan", "while", "while"]


def test_autoreset_restarts_only_the_rows_asked_for(ticker, starts_batch):
    """Rows of the batch of starts restarted with other keys: the rows asked for become the new
    keys' starts (another pool entry and seed), the others stay as they were, bit for bit."""
    env, params, keys, obs, states = starts_batch
    _, _, reset = ticker(NOOP_MAX)
    new_keys = jax.random.split(jax.random.key(5), BATCH)
    mask = np.arange(BATCH) % 3 == 0
    new_obs, new = jax.jit(jax.vmap(env.autoreset, in_axes=(0, 0, 0, 0, None)))(new_keys, mask, obs, states, params)
    fresh_obs, fresh = reset(new_keys, params)
    assert (noop_counts(fresh) != noop_counts(states)).any()  # the new starts are other starts
    for got, restarted, kept in zip(jax.tree.leaves((new_obs, new)), jax.tree.leaves((fresh_obs, fresh)),
                                    jax.tree.leaves((obs, states))):
        got, restarted, kept = np.asarray(got), np.asarray(restarted), np.asarray(kept)
        rows = mask.reshape(-1, *[1] * (got.ndim - 1))
        np.testing.assert_array_equal(got, np.where(rows, restarted, kept))


def test_the_pool_has_noop_max_plus_one_counts_of_variants():
    template = jax.tree.map(np.asarray, octax_core.Machine().boot(TICKER_ROM, jax.random.key(0)))
    step = jax.jit(jax.vmap(lambda s: octax_core.Machine().run_frames(s, 0, FRAMES)))
    pool = starts.noop_pool(template, step, 2, variants=3)
    assert pool.V.shape == (9, 16)
    np.testing.assert_array_equal(pool.V[:, 1], [0, 0, 0, 4, 4, 4, 8, 8, 8])
    assert starts.noop_pool(template, step, 0).V.shape == (1, 16)
