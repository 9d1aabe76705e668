"""Registers every game of the core registry with Gymnasium as `octax/<Id>-v<version>`.

Gymnasium 1.x has no plugin auto-registration; as with ale-py, importing the package registers
the ids (`import octax_gym; gymnasium.register_envs(octax_gym)` keeps linters from dropping the
import). Each id has an `entry_point` (`gymnasium.make` -> `OctaxEnv`) and a `vector_entry_point`
(`gymnasium.make_vec` -> `OctaxVectorEnv`, one batched JAX call instead of N envs in a loop).
"""

from __future__ import annotations

import gymnasium

from octax_core.games import get_spec, list_games

NAMESPACE = "octax"


def env_id(game: str) -> str:
    """The Gymnasium id of a registered game, e.g. "Pong" -> "octax/Pong-v0"."""
    return f"{NAMESPACE}/{game}-v{get_spec(game).version}"


def register_all() -> list[str]:
    """Registers (or re-registers) every game; returns the Gymnasium ids."""
    ids = []
    for game in list_games():
        gym_id = env_id(game)
        gymnasium.register(
            id=gym_id,
            entry_point="octax_gym.env:OctaxEnv",
            vector_entry_point="octax_gym.vector:OctaxVectorEnv",
            kwargs={"game": game},
            # Truncation is the env's own (`max_episode_steps=` keyword, the game's default
            # otherwise), counted inside the jitted step, so no TimeLimit wrapper is added.
            max_episode_steps=None,
            disable_env_checker=False,
        )
        ids.append(gym_id)
    return ids
