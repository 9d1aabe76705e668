"""Many agents in one program: every function of one agent mapped over a leading agent axis.

A run of G games x S seeds trains G x S independent agents (game-major: agent g * S + i plays game
g with seed `seed + i`). Each function of the loop is written for one agent and mapped here over
the agents, inside one compiled program. With one agent the function runs unmapped on the lone
agent's slice, so a lone run is the plain program. Agent (g, seed)'s keys come from
`jax.random.key(seed)` alone (`agent_keys`) and its network's width does not depend on the run's
games (networks.py), so it learns what a run of that game and seed alone learns.

How the agents are mapped (`TrainConfig.agent_map`):

* "vmap": `jax.vmap`, the agents' env steps and matrix products batched together: what a GPU
  needs to be busy. Agents match lone runs to float tolerance, not bit for bit: XLA sums a
  vmapped reduction over the batch axis (a bias gradient, a LayerNorm mean) in another order
  than the same reduction unmapped (measured on XLA:CPU: params 8e-7 apart after 4 PPO updates),
  and a near-tie in a sampled action later sends two runs apart.
* "map": `lax.map`, agent after agent inside the program: each agent runs the lone program's
  own operations, so it matches a lone run bit for bit (tests/train check it, rows and params).
  On a CPU little is lost: the work is already batched over each agent's envs.
* "auto" (the default): "map" on a CPU, "vmap" elsewhere.
"""

from __future__ import annotations

from typing import Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np

AGENT_AXIS = "agents"  # the vmap axis name, for `any_over_agents`


def vmapped(agent_map: str, num_agents: int) -> bool:
    """Whether agents share a vmap axis (so `any_over_agents` may reduce over it)."""
    if num_agents == 1:
        return False
    return agent_map == "vmap" or (agent_map == "auto" and jax.default_backend() != "cpu")


def any_over_agents(flags: jax.Array, shared: bool) -> jax.Array:
    """Whether any of `flags` is set, in this agent's envs or, when `shared` (agents vmapped), in any agent's.

    For a `lax.cond` that should stay a branch under the agent vmap: with a per-agent predicate
    `vmap` turns a cond into a select that runs both branches every time (the truncation
    bootstrap's network pass on every step: 9% of an agent's time, measured), while a predicate
    shared by all agents (a `psum` over the agent axis) keeps it a cond.
    """
    count = flags.any().astype(jnp.int32)
    if shared:
        count = jax.lax.psum(count, AGENT_AXIS)
    return count > 0


def over_agents(fn: Callable, num_agents: int, agent_map: str = "auto", in_axes=0) -> Callable:
    """`fn` mapped over a leading agent axis (see the module docstring); `in_axes` as vmap's
    (0 or None per argument). For one agent, `fn` itself on the lone agent's slice."""
    axes = in_axes if isinstance(in_axes, tuple) else None

    def mapped_args(args):
        return [a if axes is not None and axes[i] is None else None for i, a in enumerate(args)]

    if num_agents > 1 and vmapped(agent_map, num_agents):
        return jax.vmap(fn, in_axes=in_axes, axis_name=AGENT_AXIS)
    if num_agents > 1:
        def one_by_one(*args):
            fixed = mapped_args(args)
            per_agent = tuple(None if f is not None else a for f, a in zip(fixed, args))
            return jax.lax.map(lambda xs: fn(*[f if f is not None else x for f, x in zip(fixed, xs)]), per_agent)
        return one_by_one

    def lone(*args):
        sliced = [a if axes is not None and axes[i] is None else jax.tree.map(lambda x: x[0], a)
                  for i, a in enumerate(args)]
        return jax.tree.map(lambda x: x[None], fn(*sliced))

    return lone


def init_agents(init: Callable, keys: jax.Array, games: Sequence[int]):
    """`init(key, game)` for each agent, the results stacked along a leading agent axis.

    One call per agent rather than `jax.vmap(init)`: mapped over keys, initialising the network
    never returned on XLA's CPU backend here (jax 0.10.2; each layer mapped alone ran, the whole
    did not; cause not found). It is done once, and each agent gets exactly what a lone run gets.
    The stacking is numpy's: `jnp.stack` compiles a program per leaf shape (27 s for a runner).
    """
    from octax_gym.train.checkpoints import is_key, keys_as_data

    init = jax.jit(init)
    runners = [init(k, jnp.int32(g)) for k, g in zip(keys, games)]
    stacked = jax.tree.map(lambda *leaves: np.stack(leaves), *[jax.device_get(keys_as_data(r)) for r in runners])
    return jax.tree.map(lambda t, x: jax.random.wrap_key_data(x, impl=jax.random.key_impl(t)) if is_key(t)
                        else jnp.asarray(x), runners[0], stacked)


def agent_keys(seeds: Sequence[int]) -> tuple[jax.Array, jax.Array]:
    """Per agent (each (num_agents,)): the training key and the evaluation key, from
    `jax.random.key(seed)` as a run of that seed alone makes them."""
    keys = jnp.stack([jax.random.split(jax.random.key(s), 3) for s in seeds])
    return keys[:, 0], keys[:, 1]
