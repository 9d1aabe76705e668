"""No-op starts and the one env loop: what a reset draws, and what it costs.

The Ticker test game counts frames in V1, so a reset's state says how many no-op steps it
started after: V1 = 3 (start-up) + 4 x (no-op steps).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.env import starts
from ticker_game import STARTUP_FRAMES, TICKER, TICKER_ROM

FRAMES = 4


@pytest.fixture(scope="module")
def ticker_rom(tmp_path_factory):
    path = tmp_path_factory.mktemp("ticker") / "ticker.ch8"
    path.write_bytes(TICKER_ROM)
    return path


@pytest.fixture(scope="module")
def ticker(ticker_rom):
    """make() plus a jitted batched reset, built once per noop_max."""
    cache = {}

    def build(noop_max, **options):
        key = (noop_max, tuple(sorted(options.items())))
        if key not in cache:
            env, params = octax_core.make(TICKER, rom=ticker_rom, noop_max=noop_max, **options)
            cache[key] = env, params, jax.jit(jax.vmap(env.reset, in_axes=(0, None)))
        return cache[key]
    return build


def noop_counts(states) -> np.ndarray:
    return (np.asarray(states.machine.V[:, 1]).astype(int) - STARTUP_FRAMES) // FRAMES


def test_no_op_counts_are_uniform_over_0_to_noop_max(ticker):
    env, params, reset = ticker(7)
    _, states = reset(jax.random.split(jax.random.key(0), 4000), params)
    frames = np.asarray(states.machine.V[:, 1]).astype(int)
    assert set((frames - STARTUP_FRAMES) % FRAMES) == {0}  # whole steps only
    counts = np.bincount(noop_counts(states), minlength=8)
    assert len(counts) == 8 and counts.min() > 0  # every count 0..7 drawn, none beyond
    assert counts.min() > 4000 / 8 * 0.8 and counts.max() < 4000 / 8 * 1.2  # uniform (expected 500 each)


def test_noop_max_0_starts_every_episode_at_the_template(ticker):
    _, params, reset = ticker(0)
    _, states = reset(jax.random.split(jax.random.key(1), 64), params)
    assert set(noop_counts(states)) == {0}


def test_a_start_is_the_template_after_its_no_op_steps_with_a_fresh_seed(ticker):
    """The pool's entry for k no-op steps is the state that k real no-op steps reach, except
    its CXNN seed, which each episode draws from its reset key."""
    env, params, reset = ticker(5)
    alone, _, _ = ticker(0)
    step = jax.jit(alone.step_env)
    _, states = reset(jax.random.split(jax.random.key(2), 256), params)
    by_count = {}
    for i, k in enumerate(noop_counts(states)):
        by_count.setdefault(int(k), i)
    assert sorted(by_count) == list(range(6))
    _, walked = alone.reset(jax.random.key(3), params)
    for k in range(6):
        row = jax.tree.map(lambda x: x[by_count[k]], states.machine)
        for name in ("memory", "V", "I", "pc", "sp", "stack", "delay_timer", "sound_timer", "screen", "key_wait"):
            if name == "V":  # V5 holds the pool's last random draw, which the pool's seed decided
                np.testing.assert_array_equal(np.delete(row.V, 5), np.delete(walked.machine.V, 5))
            else:
                np.testing.assert_array_equal(getattr(row, name), getattr(walked.machine, name), err_msg=f"{name} after {k}")
        _, walked, *_ = step(jax.random.key(k), walked, 0, params)
    rngs = np.asarray(states.machine.rng)
    assert len(set(rngs.tolist())) == len(rngs)  # every episode its own seed


def test_the_same_key_gives_the_same_start_whatever_the_batch(ticker):
    env, params, reset = ticker(5)
    keys = jax.random.split(jax.random.key(4), 9)
    _, batch = reset(keys, params)
    for i in (0, 4, 8):
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
    # From 25 instructions a frame skip_idle (the default) runs the same loop over instruction chunks.
    env, params, _ = ticker(noop_max, autoreset=True, instructions_per_frame=100)
    _, state = env.reset(jax.random.key(0), params)
    step = jax.make_jaxpr(env.step)(jax.random.key(1), state, 1, params)
    assert _loops(step.jaxpr) == ["while", "scan", "while", "while"]


def test_autoreset_restarts_only_the_rows_asked_for(ticker):
    env, params, reset = ticker(3)
    keys = jax.random.split(jax.random.key(5), 4)
    obs, states = reset(keys, params)
    step = jax.vmap(env.step_env, in_axes=(0, 0, 0, None))
    obs, states, *_ = step(keys, states, jnp.zeros(4, jnp.int32), params)
    mask = jnp.array([True, False, True, False])
    new_obs, new = jax.vmap(env.autoreset, in_axes=(0, 0, 0, 0, None))(keys, mask, obs, states, params)
    fresh_obs, fresh = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
    for i in range(4):
        expect_obs, expect = (fresh_obs, fresh) if mask[i] else (obs, states)
        np.testing.assert_array_equal(np.asarray(new_obs[i]), np.asarray(expect_obs[i]))
        for a, b in zip(jax.tree.leaves(new), jax.tree.leaves(expect)):
            np.testing.assert_array_equal(np.asarray(a[i]), np.asarray(b[i]))


def test_the_pool_has_noop_max_plus_one_counts_of_variants():
    template = jax.tree.map(np.asarray, octax_core.Machine().boot(TICKER_ROM, jax.random.key(0)))
    step = jax.jit(jax.vmap(lambda s: octax_core.Machine().run_frames(s, 0, FRAMES)))
    pool = starts.noop_pool(template, step, 2, variants=3)
    assert pool.V.shape == (9, 16)
    np.testing.assert_array_equal(pool.V[:, 1], [0, 0, 0, 4, 4, 4, 8, 8, 8])
    assert starts.noop_pool(template, step, 0).V.shape == (1, 16)
