"""octax_gym.train.envs.Lanes: a lane of a many-game mix, fixed to its game, plays step for step what
`octax_core.make(game, autoreset=True)` plays from the same keys and actions (its autoresets
included), whichever games share the mix; the evaluation lanes start from distinct no-op starts."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core

pytest.importorskip("flax")
from octax_gym.train.envs import Lanes  # noqa: E402
from octax_gym.train.networks import ACTIONS  # noqa: E402

STEPS, ENVS, CAP = 40, 3, 12  # a 12-step cap: every lane restarts three times


@pytest.fixture(scope="module")
def lanes():
    return Lanes(["Airplane", "Deep8"], {"max_episode_steps": CAP}, eval_noop_max=30)


@functools.partial(jax.jit, static_argnums=0)
def _lane_rollout(lanes, game, key, actions):
    """The lanes' trajectory (obs, reward, terminated, truncated) and last state; one program for
    every game (`game` is an argument)."""
    reset_key, key = jax.random.split(key)
    obs, state = lanes.reset(reset_key, game, ENVS)

    def step(carry, action):
        key, obs, state = carry
        key, step_key = jax.random.split(key)
        obs, state, reward, terminated, truncated, _ = lanes.step(step_key, state, action)
        return (key, obs, state), (obs, reward, terminated, truncated)

    (_, _, state), trajectory = jax.lax.scan(step, (key, obs, state), actions)
    return trajectory, state


def _alone_rollout(env, params, key, actions):
    def run(key, actions):
        reset_key, key = jax.random.split(key)
        obs, state = jax.vmap(env.reset, in_axes=(0, None))(jax.random.split(reset_key, ENVS), params)

        def step(carry, action):
            key, obs, state = carry
            key, step_key = jax.random.split(key)
            obs, state, reward, terminated, truncated, _ = jax.vmap(env.step, in_axes=(0, 0, 0, None))(
                jax.random.split(step_key, ENVS), state, action, params)
            return (key, obs, state), (obs, reward, terminated, truncated)

        return jax.lax.scan(step, (key, obs, state), actions)[1]
    return jax.jit(run, compiler_options=env.compiler_options)(key, actions)


def test_a_lane_of_the_mix_plays_what_its_game_plays_alone(lanes):
    env, params = octax_core.make("Deep8", autoreset=True, max_episode_steps=CAP)
    key = jax.random.key(7)
    actions = np.random.default_rng(8).integers(0, env.num_actions, (STEPS, ENVS)).astype(np.int32)  # drawn on the host
    mine, _ = _lane_rollout(lanes, 1, key, actions)
    theirs = _alone_rollout(env, params, key, actions)
    for name, a, b in zip(("obs", "reward", "terminated", "truncated"), mine, theirs):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b), err_msg=name)
    assert np.asarray(theirs[3]).sum() >= ENVS * 3  # the autoresets were exercised


def test_every_reset_keeps_the_lanes_game(lanes):
    """Airplane's lanes, the other game of the mix (the program of the test above, `game` its argument)."""
    (_, _, terminated, truncated), state = _lane_rollout(lanes, 0, jax.random.key(0), np.zeros((STEPS, ENVS), np.int32))
    assert (np.asarray(terminated) | np.asarray(truncated)).sum() >= ENVS * 3  # every lane restarted, again and again
    assert np.asarray(state.game).tolist() == [0] * ENVS and int(np.asarray(state.episode_step).max()) < CAP


def test_legal_actions_are_each_games_own(lanes):
    assert lanes.legal.shape == (2, ACTIONS)
    assert lanes.legal.sum(axis=1).tolist() == [2, 4]  # Airplane: no-op + 1 key; Deep8: no-op + 3 keys


def _distinct_machines(state, count: int) -> int:
    """How many of `count` envs' machines differ (their random seeds left out)."""
    leaves = [np.asarray(x).reshape(count, -1) for x in jax.tree.leaves(state.machine)
              if not jnp.issubdtype(x.dtype, jax.dtypes.prng_key) and x.dtype != np.uint32]
    return len({row.tobytes() for row in np.concatenate(leaves, axis=1)})


def test_evaluation_episodes_start_apart_and_training_ones_do_not(lanes):
    evaluation, training = jax.jit(lambda k: (lanes.reset(k, 1, 16, evaluation=True)[1], lanes.reset(k, 1, 16)[1]))(
        jax.random.key(0))  # both resets in one program
    assert _distinct_machines(evaluation, 16) > 4  # 0..30 no-op starts
    assert _distinct_machines(training, 16) == 1  # the run's env: no no-op starts unless asked
