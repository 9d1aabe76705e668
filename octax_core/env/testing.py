"""A contract suite for envs, reusable on your own `GameSpec` (as pgx's api_test and jumanji's
env smoke tests are for theirs).

    from octax_core.env.testing import check_env
    check_env("Pong")                        # a registered game
    check_env(my_spec, rom="my_game.ch8")    # your own

`check_env` raises `AssertionError` naming the broken promise.
"""

from __future__ import annotations

from typing import Union

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.env.environment import Env, EnvParams, make
from octax_core.env.games import GameSpec


def check_env(game: Union[str, GameSpec], *, num_envs: int = 3, steps: int = 12, seed: int = 0,
              rom=None, **overrides) -> None:
    """Runs the env contract on `game` with random actions.

    Checks: observation shape, dtype and pixel values; reward/flag dtypes and shapes; info keys;
    finite rewards; determinism (same keys, same trajectory); batch-size independence (env i of
    a batch equals the same env run alone); no retracing across steps; out-of-range actions
    refused.

    Raises:
        AssertionError: a broken promise, named in the message.
    """
    env, params = make(game, rom=rom, **overrides)
    keys = jax.random.split(jax.random.key(seed), num_envs)
    actions = jax.random.randint(jax.random.key(seed + 1), (steps, num_envs), 0, env.num_actions)
    traces = []

    def counted_step(key, state, action, params):
        traces.append(None)  # runs once per trace, never per call
        return env.step(key, state, action, params)

    reset = jax.jit(jax.vmap(env.reset, in_axes=(0, None)), compiler_options=env.compiler_options)
    step = jax.jit(jax.vmap(counted_step, in_axes=(0, 0, 0, None)), compiler_options=env.compiler_options)
    _check_outputs(env, params, reset, step, keys)
    _check_action_refused(env, params, reset, keys)
    batched = _rollout(reset, step, params, keys, actions)
    again = _rollout(reset, step, params, keys, actions)
    _assert_trees_equal(batched, again, "the same keys and actions gave different trajectories")
    assert len(traces) == 1, f"step was traced {len(traces)} times over {2 * steps + 1} calls; expected once"
    alone = _rollout(reset, step, params, keys[:1], actions[:, :1])
    _assert_trees_equal(jax.tree.map(lambda x: x[:, :1], batched), alone,
                        "env 0 of a batch differs from the same env run alone: batch size leaks in")
    rewards = np.asarray(batched[1])
    assert np.all(np.isfinite(rewards)), f"{env.spec.id}: non-finite rewards {rewards[~np.isfinite(rewards)]}"


def _check_outputs(env: Env, params: EnvParams, reset, step, keys) -> None:
    """Shapes, dtypes, pixel values and info keys of one batched reset and step."""
    name, n = env.spec.id, len(keys)
    obs, state = reset(keys, params)
    assert obs.shape == (n, *env.observation_shape), f"{name}: reset obs shape {obs.shape[1:]} != {env.observation_shape}"
    assert obs.dtype == jnp.uint8, f"{name}: obs dtype {obs.dtype} != uint8"
    high = env.observation_high  # XO-CHIP: a code per plane combination, 0..3 (or 0, 85, 170, 255)
    valid = set(range(0, high + 1, high // 3)) if env.machine.platform.planes > 1 else {0, high}
    assert set(np.unique(np.asarray(obs))) <= valid, f"{name}: obs pixels {set(np.unique(np.asarray(obs)))} not in {valid}"
    obs, state, reward, terminated, truncated, info = step(keys, state, jnp.zeros(n, jnp.int32), params)
    assert obs.shape == (n, *env.observation_shape) and obs.dtype == jnp.uint8, f"{name}: step obs {obs.shape} {obs.dtype}"
    assert reward.shape == (n,) and reward.dtype == jnp.float32, f"{name}: reward {reward.shape} {reward.dtype}"
    for flag_name, flag in (("terminated", terminated), ("truncated", truncated)):
        assert flag.shape == (n,) and flag.dtype == jnp.bool_, f"{name}: {flag_name} {flag.shape} {flag.dtype}"
    missing = {"score", "lives", "episode_step"} - set(info)
    assert not missing, f"{name}: info lacks {sorted(missing)}"
    assert np.all(np.asarray(info["episode_step"]) == 1), f"{name}: episode_step after one step is not 1"


def _check_action_refused(env: Env, params: EnvParams, reset, keys) -> None:
    state = jax.tree.map(lambda x: x[0], reset(keys, params)[1])
    for bad in (-1, env.num_actions):
        try:
            env.step(jax.random.key(0), state, bad, params)
        except ValueError:
            continue
        raise AssertionError(f"{env.spec.id}: action {bad} was accepted; valid 0..{env.num_actions - 1}")


def _rollout(reset, step, params: EnvParams, keys, actions):
    """(obs, reward, terminated, truncated) per step for a batch; step keys derive from `keys`."""
    obs, state = reset(keys, params)
    step_keys = jax.vmap(lambda k: jax.random.split(k, len(actions)))(keys)  # (envs, steps)
    out = []
    for t, action in enumerate(actions):
        obs, state, reward, terminated, truncated, _ = step(step_keys[:, t], state, action, params)
        out.append((obs, reward, terminated, truncated))
    return tuple(np.stack([np.asarray(o[i]) for o in out]) for i in range(4))


def _assert_trees_equal(a, b, message: str) -> None:
    for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b)):
        x, y = np.asarray(x), np.asarray(y)
        assert np.array_equal(x, y, equal_nan=np.issubdtype(x.dtype, np.floating)), message
