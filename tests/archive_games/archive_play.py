"""Plays an archive game under a policy, for the per-game tests: one jitted scan per call.

`play(game, policy, steps=..., num_envs=...)` runs `num_envs` envs side by side with autoreset,
so a batch plays several episodes, and returns every step's reward, flags and score. A policy is
a jittable function `(EnvState of one env, key) -> action`; `random_policy(n)` plays uniformly.
Scripted policies read the machine (`state.machine.V`, `.pc`, `ram_value(state.machine, a)`).
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Optional

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.env import make

Policy = Callable[[object, jax.Array], jax.Array]


def random_policy(num_actions: int) -> Policy:
    return lambda state, key: jax.random.randint(key, (), 0, num_actions)


def constant_policy(action: int) -> Policy:
    return lambda state, key: jnp.int32(action)


@dataclasses.dataclass
class Played:
    """Per step (steps, num_envs): reward, terminated, truncated, the score and lives in info."""

    rewards: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    score: np.ndarray
    lives: np.ndarray

    @property
    def episodes_ended(self) -> int:
        return int(self.terminated.sum())

    def returns(self) -> list[float]:
        """The return of every episode that terminated or was truncated, in order per env."""
        out = []
        for env in range(self.rewards.shape[1]):
            total = 0.0
            for t in range(self.rewards.shape[0]):
                total += float(self.rewards[t, env])
                if self.terminated[t, env] or self.truncated[t, env]:
                    out.append(total)
                    total = 0.0
        return out


def play(game, policy: Optional[Policy] = None, *, steps: int, num_envs: int = 2, seed: int = 0,
         **options) -> Played:
    """Plays `steps` env steps in each of `num_envs` envs (autoreset) and returns what happened."""
    env, params = make(game, autoreset=True, **options)
    policy = policy or random_policy(env.num_actions)

    def one(key, state):
        act_key, step_key = jax.random.split(key)
        action = policy(state, act_key)
        _, state, reward, terminated, truncated, info = env.step(step_key, state, action, params)
        return state, (reward, terminated, truncated, info["score"], info["lives"])

    @jax.jit
    def run(keys):
        _, states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)

        def body(states, t):
            step_keys = jax.vmap(jax.random.fold_in, in_axes=(0, None))(keys, t)
            return jax.vmap(one)(step_keys, states)
        return jax.lax.scan(body, states, jnp.arange(steps))[1]

    keys = jax.random.split(jax.random.key(seed), num_envs)
    return Played(*(np.asarray(x) for x in run(keys)))
