"""The compiled programs behind the Gymnasium envs: one jitted call per reset and per step.

Both envs (`OctaxEnv`, `OctaxVectorEnv`) build on the functional core (`octax_core.make`, with its
own autoreset off) and differ only in batching and host conversions. The pieces here are shared so
that a single env and row i of a vector env draw the same random numbers in the same order:

* every env carries its own PRNG key; each step splits it three ways (next key, step key, reset
  key), so one env's randomness never depends on how many envs run beside it;
* a reset with seed s starts env i's chain at `jax.random.key(s + i)` (Gymnasium's `SyncVectorEnv`
  seeds its sub-envs s, s+1, ...), so row i equals a single env reset with seed s + i;
* autoreset (Gymnasium's NEXT_STEP or SAME_STEP) runs inside the step, behind one batch-level
  `lax.cond`: the reset work is paid only on steps where some episode ended.

Programs are cached per (game, config, ROM), so every env of one game shares its compilations.
"""

from __future__ import annotations

import functools
from typing import Any, Optional

import jax
import jax.numpy as jnp
import numpy as np
from gymnasium.vector import AutoresetMode

import octax_core
from octax_core.env.environment import Env, EnvConfig, EnvParams, EnvState
from octax_core.env.games import GameSpec


def advance(key: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """One env's key -> (its next key, a key for this step, a key for a reset in this step)."""
    next_key, step_key, reset_key = jax.random.split(key, 3)
    return next_key, step_key, reset_key


def _select(mask: jax.Array, on_true, on_false):
    """Row-wise select over pytrees whose leaves have the batch as their first axis."""
    def pick(a, b):
        return jnp.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b)
    return jax.tree.map(pick, on_true, on_false)


class Program:
    """The jitted reset and step of one game and config, for any batch size."""

    def __init__(self, env: Env):
        self.env = env
        self.info = jax.vmap(env.info)
        self.reset = jax.jit(self._reset)
        self.step = {mode: jax.jit(functools.partial(self._step, mode=mode), donate_argnums=(1,))
                     for mode in AutoresetMode}

    # batched: keys (N,), state EnvState with (N, ...) leaves

    def _reset(self, keys, state: Optional[EnvState], obs, mask, params: EnvParams):
        """Resets the rows in `mask` (all rows when `state` is None); returns keys, obs, state, info."""
        next_keys, _, reset_keys = jax.vmap(advance)(keys)
        fresh_obs, fresh = jax.vmap(self.env.reset, in_axes=(0, None))(reset_keys, params)
        if state is not None:
            fresh_obs, fresh = _select(mask, (fresh_obs, fresh), (obs, state))
            next_keys = select_keys(mask, next_keys, keys)
        return next_keys, fresh_obs, fresh, self._with_masks(self.info(fresh))

    def _step(self, keys, state: EnvState, actions, params: EnvParams, *, mode: AutoresetMode):
        next_keys, step_keys, reset_keys = jax.vmap(advance)(keys)
        was_done = state.done
        obs, state, reward, terminated, truncated, info = jax.vmap(
            self.env.step, in_axes=(0, 0, 0, None))(step_keys, state, actions, params)
        if mode == AutoresetMode.NEXT_STEP:
            # The step after an episode's end is its reset: the action is ignored, and the core
            # already gave the ended (standing-still) row reward 0; its flags are cleared here.
            obs, state = self._reset_where(was_done, reset_keys, obs, state, params)
            terminated, truncated = terminated & ~was_done, truncated & ~was_done
            info = self.info(state)
        elif mode == AutoresetMode.SAME_STEP:
            ended = state.done
            final = {"final_obs": obs, "_final_obs": ended,
                     "final_info": self._with_masks(info), "_final_info": ended}
            obs, state = self._reset_where(ended, reset_keys, obs, state, params)
            return next_keys, obs, state, reward, terminated, truncated, {**self._with_masks(self.info(state)), **final}
        return next_keys, obs, state, reward, terminated, truncated, self._with_masks(info)

    def _reset_where(self, mask, reset_keys, obs, state, params):
        def reset_rows(operands):
            obs, state = operands
            fresh = jax.vmap(self.env.reset, in_axes=(0, None))(reset_keys, params)
            return _select(mask, fresh, (obs, state))
        return jax.lax.cond(jnp.any(mask), reset_rows, lambda operands: operands, (obs, state))

    @staticmethod
    def _with_masks(info: dict) -> dict:
        """Gymnasium's vector-info convention: each key `k` comes with a bool mask `_k`."""
        return {**info, **{f"_{name}": jnp.ones(value.shape[:1], jnp.bool_) for name, value in info.items()}}


def select_keys(mask, on_true, on_false):
    """Row-wise select between two batches of typed PRNG keys."""
    data = _select(mask, jax.random.key_data(on_true), jax.random.key_data(on_false))
    return jax.random.wrap_key_data(data, impl=jax.random.key_impl(on_true))


@functools.lru_cache(maxsize=64)
def _program(spec: GameSpec, config: EnvConfig, rom: Optional[str]) -> Program:
    return Program(Env(spec, config, rom))


CORE_OPTIONS = ("frames_per_step", "instructions_per_frame", "obs_scale", "freeze_timers")
PARAM_OPTIONS = ("max_episode_steps", "repeat_action_probability", "noop_max")


def build(game: Any, rom, options: dict[str, Any]) -> tuple[Program, EnvParams]:
    """The cached program and checked params for a game id or `GameSpec` and the env options.

    `options` holds the env keywords; None means the game's default.
    """
    spec = game if isinstance(game, GameSpec) else octax_core.get_spec(_check_game(game))
    given = {name: value for name, value in options.items() if value is not None}
    config, params = octax_core.make_config(spec, autoreset=False, **given)  # checks every value
    return _program(spec, config, None if rom is None else str(rom)), params


def _check_game(game) -> str:
    if not isinstance(game, str):
        raise TypeError(f"game must be a registered id (str) or a GameSpec, got {type(game).__name__}")
    return game


def seeds_for(seed, num_envs: int) -> list[int]:
    """Per-env seeds as Gymnasium's SyncVectorEnv makes them: an int s gives s, s+1, ...; a list
    gives one per env."""
    def valid(s):
        return isinstance(s, (int, np.integer)) and not isinstance(s, bool) and 0 <= s < MAX_SEED

    if valid(seed) and seed + num_envs <= MAX_SEED:
        return [int(seed) + i for i in range(num_envs)]
    if isinstance(seed, (list, tuple)) and len(seed) == num_envs and all(valid(s) for s in seed):
        return [int(s) for s in seed]
    raise ValueError(f"seed must be None, an int in 0..2**32 - num_envs, or a list of {num_envs} ints in "
                     f"0..2**32 - 1, got {seed!r}")


MAX_SEED = 2**32  # seeds become uint32 JAX PRNG seeds


def keys_from_seeds(seeds: list[int]) -> jax.Array:
    return jax.vmap(jax.random.key)(jnp.asarray(seeds, jnp.uint32))
