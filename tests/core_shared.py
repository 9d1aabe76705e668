"""Programs shared by tests/core_env and tests/core_emulator (only their files import this module).

`env_rollout` is a vmapped env's reset and scanned steps under given keys and actions. Tests of
both folders that play the same game with the same `make` options at the same sizes run the one
compiled program it returns (a cold compile of an XO-CHIP env rollout costs seconds):
test_skip_idle_envs.py's skipping rollout of Civiliz8n is test_compiler_options.py's plain one.
"""

from __future__ import annotations

import functools

import jax

import octax_core

# The shared rollout's sizes: envs in the batch, steps after the reset.
ROLLOUT_ENVS, ROLLOUT_STEPS = 2, 40


def rollout_of(env, params):
    """`rollout(keys, actions)`: len(keys[0]) envs reset from keys[0], then a step per row of
    `actions` (keys[1:] the step keys): (reset obs, (obs, reward, terminated, truncated, info)
    per step, final state)."""
    step = jax.vmap(env.step, in_axes=(0, 0, 0, None))
    reset = jax.vmap(env.reset, in_axes=(0, None))

    def rollout(keys, actions):
        obs, state = reset(keys[0], params)

        def body(state, xs):
            step_keys, action = xs
            obs, state, reward, terminated, truncated, info = step(step_keys, state, action, params)
            return state, (obs, reward, terminated, truncated, info)

        state, trajectory = jax.lax.scan(body, state, (keys[1:], actions))
        return obs, trajectory, state

    return rollout


# Two entries: a game's pair (skip_idle on and off) stays alive together; every game of the slow
# registry-wide test passes through here, and keeping all their programs grew a worker past what
# CI's machine holds.
@functools.lru_cache(maxsize=2)
def env_rollout(game: str, **options):
    """`make(game, **options)` and its `rollout_of`, plain-jitted: (env, params, jitted rollout).
    Callers that share it pass keys of shape (ROLLOUT_STEPS + 1, ROLLOUT_ENVS) and int32 actions
    of shape (ROLLOUT_STEPS, ROLLOUT_ENVS)."""
    env, params = octax_core.make(game, **options)
    return env, params, jax.jit(rollout_of(env, params))
