"""Registers every game of the core registry with Gymnasium as `octax/<Id>-v<version>`.

Gymnasium 1.x has no plugin auto-registration; as with ale-py, importing the package registers
the ids (`import octax_gym; gymnasium.register_envs(octax_gym)` keeps linters from dropping the
import). Each id has an `entry_point` (`gymnasium.make` -> `OctaxEnv`) and a `vector_entry_point`
(`gymnasium.make_vec` -> `OctaxVectorEnv`, one batched JAX call instead of N envs in a loop).

The two-player games (`list_games(players=2)`) are registered too, the same way: with
`opponent=` an id is one seat against a fixed opponent (`octax_gym.step.opponent`); a game that is
not a one-player env (`GameSpec.solo` False) raises `OpponentRequiredError` without it.

Each game's spec carries its episode bound, `max_episode_steps` (the game's own, 4,500 steps for
most), so `env.spec.max_episode_steps` says where episodes are cut, as Gymnasium users read it.
Its kwargs hold the env's keyword of that name as None, which says "the game's own, unless told",
and makes each of Gymnasium's makers count the steps once: `make_vec` builds `OctaxVectorEnv`,
which counts them inside the jitted step (its `max_episode_steps=` keyword, when given, replaces
the None); `make` wraps the single env in Gymnasium's `TimeLimit` (the spec's number, or the one
given to `make`), and the env, seeing the None, lifts its own bound (`OctaxEnv.spec`), so that
`make(id, max_episode_steps=M)` cuts episodes at M, more steps than the game's default included.
The mix's spec has no bound: each game of a mix keeps its own.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Optional, Union

import gymnasium

from octax_core.env.games import GameSpec, get_spec, list_games
from octax_gym.envs.game_names import NAMESPACE, env_id  # noqa: F401  (where benchmarks and users import them)


def register_all() -> list[str]:
    """Registers (or re-registers) every one-player game; returns the Gymnasium ids."""
    return [_register(game) for game in list_games()]


def register_two_player() -> list[str]:
    """Registers (or re-registers) every two-player game (`list_games(players=2)`), those that are
    not one-player envs included; returns their Gymnasium ids."""
    solo = set(list_games())  # registered by `register_all` already
    return [env_id(game) if game in solo else _register(game) for game in list_games(players=2)]


MIX_ENV_ID = f"{NAMESPACE}/Mix-v0"


def register_mix() -> str:
    """Registers `octax/Mix-v0`: many games in one batch (`octax_core.make_mix`), given as
    `games=[...]` (or a named mix, "octax16", the default) and `weights=`."""
    gymnasium.register(
        id=MIX_ENV_ID,
        entry_point="octax_gym.envs.env:OctaxEnv",
        vector_entry_point="octax_gym.envs.vector:OctaxVectorEnv",
        kwargs={"game": "octax16"},
        max_episode_steps=None,  # no one number: each game of a mix keeps its own bound
        disable_env_checker=False,
    )
    return MIX_ENV_ID


def _register(game: str) -> str:
    gym_id = env_id(game)
    gymnasium.register(
        id=gym_id,
        entry_point="octax_gym.envs.env:OctaxEnv",
        vector_entry_point="octax_gym.envs.vector:OctaxVectorEnv",
        kwargs={"game": game, "max_episode_steps": None},  # see the module docstring
        max_episode_steps=get_spec(game).max_episode_steps,
        disable_env_checker=False,
    )
    return gym_id


def register_game(spec: GameSpec, rom: Optional[Union[str, os.PathLike]] = None) -> str:
    """Registers your own game (a `GameSpec` not in the core registry) as `octax/<id>-v<version>`.

    Afterwards `gymnasium.make(id)` and `gymnasium.make_vec(id, num_envs=N)` build it like any
    built-in game. `rom` is the path of its ROM file (its SHA-1 must be `spec.rom_sha1`); without
    it the ROM store looks `spec.rom_file` up (OCTAX_ROM_DIR, the user folder, roms/).

    Returns the Gymnasium id. Raises ValueError when the id is a built-in game's (pick another
    `GameSpec.id`), FileNotFoundError when `rom` does not exist.
    """
    if not isinstance(spec, GameSpec):
        raise TypeError(f"register_game expects a GameSpec, got {type(spec).__name__}")
    if spec.id in list_games() and get_spec(spec.id) is not spec:
        raise ValueError(f"{spec.id!r} is a built-in game's id; give your GameSpec another id "
                         f"(built-in ids: {', '.join(list_games())})")
    if rom is not None and not Path(rom).is_file():
        raise FileNotFoundError(f"ROM file not found: {rom}")
    gym_id = env_id(spec)
    gymnasium.register(
        id=gym_id,
        entry_point="octax_gym.envs.env:OctaxEnv",
        vector_entry_point="octax_gym.envs.vector:OctaxVectorEnv",
        kwargs={"game": spec, "rom": None if rom is None else str(rom), "max_episode_steps": None},
        max_episode_steps=spec.max_episode_steps,
        disable_env_checker=False,
    )
    return gym_id
