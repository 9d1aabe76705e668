"""The `octax` package (0.1.1, the `dev` extra) on the same work as ours, for the ratio.

Its Pong is built as `octax.environments.create_environment("pong")` builds it, but from our ROM
path: `create_environment` looks for ROMs in a `roms/` folder above the installed package.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Optional

from harness import BenchError, Prepared, compile_rollout, state_bytes


def import_error() -> Optional[str]:
    """None when the `octax` package imports, else why not (it is the `dev` extra)."""
    try:
        import octax  # noqa: F401
    except ImportError as exc:
        return str(exc) or type(exc).__name__
    return None


def pong(rom: Path):
    """octax's Pong `OctaxEnv` over our ROM file."""
    import warnings

    from octax.env import OctaxEnv
    from octax.environments import pong as game

    # octax's scatters mix dtypes (int32 into bool, uint16 into uint8); JAX warns on every trace.
    warnings.filterwarnings("ignore", message="scatter inputs have incompatible types", category=FutureWarning)
    return OctaxEnv(
        rom_path=str(rom),
        score_fn=game.score_fn,
        terminated_fn=game.terminated_fn,
        action_set=game.action_set,
        startup_instructions=getattr(game, "startup_instructions", 0),
        custom_startup=getattr(game, "custom_startup", None),
        disable_delay=getattr(game, "disable_delay", False),
    )


def action_for_key(env, key: int) -> int:
    """octax's action holding CHIP-8 `key` (-1: its no-op, the last action)."""
    keys = [int(k) for k in env.action_set]
    if key < 0:
        return env.num_actions - 1
    if key not in keys:
        raise BenchError(f"octax Pong has no action for key {key} (keys {keys}); use --key -1, a Pong key, "
                         "or --no-octax")
    return keys.index(key)


def prepare(rom: Path, n: int, args: argparse.Namespace, autoreset: bool = False,
            max_episode_steps: Optional[int] = None) -> Prepared:
    """octax: vmapped `OctaxEnv.step(state, action)`, scanned `args.steps` times (its paper's benchmark).

    With `autoreset`, each step also resets the envs whose episode ended, the way gymnax's
    `Environment.step` (octax's training wrapper) does it: a reset for every env, then a select.
    `max_episode_steps` replaces octax's truncation bound (4500 steps).
    """
    import jax
    import jax.numpy as jnp

    env = pong(rom)
    if max_episode_steps is not None:
        env.max_num_steps_per_episodes = max_episode_steps
    keys = jax.random.split(jax.random.key(0), n)
    states, obs, _ = jax.vmap(env.reset)(keys)
    actions = jnp.full((n,), action_for_key(env, args.key), dtype=jnp.int32)

    def step(key, state, action):
        next_state, next_obs, _, terminated, truncated, _ = env.step(state, action)
        if autoreset:
            fresh_state, fresh_obs, _ = env.reset(key)
            done = terminated | truncated
            next_state, next_obs = jax.tree.map(lambda a, b: jnp.where(done, a, b),
                                                (fresh_state, fresh_obs), (next_state, next_obs))
        return next_state, next_obs

    def rollout(carry, actions):
        # The observation rides in the carry so that producing it is part of the measured step,
        # as it is in an RL loop (and in octax's own benchmark, which keeps every step's output).
        def body(carry, _):
            keys, state, _ = carry
            step_keys = keys
            if autoreset:  # only the reset draws from the keys: without it, octax's own step
                keys, step_keys = (k[:, 0] for k in jnp.split(jax.vmap(jax.random.split)(keys), 2, axis=1))
            state, obs = jax.vmap(step)(step_keys, state, actions)
            return (keys, state, obs), None
        carry, _ = jax.lax.scan(body, carry, length=args.steps)
        return carry

    run, compile_s, devices = compile_rollout(rollout, (keys, states, obs), actions, args.devices)
    return Prepared(run, compile_s, state_bytes(states), env.instructions_per_step * env.frame_skip, devices)
