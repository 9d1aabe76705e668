"""The built-in policies, one table for everything that plays a game by itself.

`video.record`, `collect_dataset` and their commands (`octax-gym record`, `octax-gym dataset
collect`, and `octax-gym trace`'s --policy choices) all take a policy the same way: None or
"random" (uniform actions), "noop" (action 0, no key held), or a function of your own, e.g. a
trained agent. A policy maps the batched observation, (num_envs, frames_per_step, H, W), to one
action per env, ints in 0..num_actions-1 of shape (num_envs,). The built-in ones ignore the
observation, and a seeded one gives the same actions for the same seed in every caller.

The built-in ones are the core's table of players (`octax_core.env.players`, which also fills the
seats of two-player games), its `SEATLESS` ones: the same traced function, here batched over the
envs and fed one key per step from `seed`'s chain.
"""

from __future__ import annotations

from typing import Any, Callable, Union

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.env import players
from octax_gym.envs.choices import check_choice

Policy = Union[None, str, Callable[[Any], Any]]
Act = Callable[[Any], Any]  # the batched observation -> one action per env

DEFAULT = "random"  # what None means
FUNCTION_HINT = "or a function from a batch of observations to a batch of actions"


def _table_policy(name: str) -> Callable[[int, int, int], Act]:
    """The table's player `name` for a batch of one-player envs: every action open, one key a step."""
    player = players.make_player(name, None)
    batched = jax.jit(jax.vmap(player, in_axes=(None, 0, None, None, None, None)))

    def build(num_envs: int, num_actions: int, seed: int) -> Act:
        legal = jnp.ones(num_actions, jnp.bool_)
        chain = [jax.random.key(seed)]

        def act(obs):
            chain[0], draw = jax.random.split(chain[0])
            actions = batched(None, jax.random.split(draw, num_envs), None, None, jnp.int32(0), legal)
            return np.asarray(actions, np.int64)
        return act
    return build


# name -> (num_envs, num_actions, seed) -> policy: "random" (uniform over the actions) and "noop"
# (action 0, no key), the core table's players that need no seat.
POLICIES: dict[str, Callable[[int, int, int], Act]] = {name: _table_policy(name) for name in players.SEATLESS}


def check_policy(policy: Policy) -> Policy:
    """`policy`, when it is a function, None or a name in `POLICIES`.

    Raises:
        UnknownOptionError: anything else; the message lists the names.
    """
    return policy if callable(policy) else check_choice("policy", policy, (None, *POLICIES), FUNCTION_HINT)


def make_policy(policy: Policy, num_envs: int, num_actions: int, seed: int) -> Act:
    """The function that plays: `policy` itself, or the built-in one it names, for this batch.

    Raises:
        UnknownOptionError: as `check_policy`.
    """
    policy = check_policy(policy)
    return policy if callable(policy) else POLICIES[policy or DEFAULT](num_envs, num_actions, seed)


def policy_name(policy: Policy) -> str:
    """A name to record with what the policy made: the built-in name or the function's."""
    if callable(policy):
        return getattr(policy, "__qualname__", type(policy).__name__)
    return policy or DEFAULT
