"""The game registry: every module in this package exports `SPECS`, a tuple of `GameSpec`.

Modules are discovered, not listed, so adding a game is adding one module. A module may name its
suite (`SUITE = "ours"`); without one its games are the octax paper's. A subpackage holds a suite
of its own (`archive/`: the Chip8 Community Archive's games): its `__init__` names the suite, and
its modules are discovered the same way. Lookups raise errors that name the valid ids (or suites).
"""

from __future__ import annotations

import importlib
import pkgutil
from typing import Optional

from octax_core.env.games.spec import (CATEGORIES, GameSpec, Seats, bcd_value, in_routine, key_mask, ram_value,
                                       register_value)

SUITES = {
    "octax": "the octax paper's suite: 21 classic CHIP-8 titles and their levels",
    "ours": "octax-gym's own games, written in Octo (roms/*.8o): Dodge and Flak, by level; Duel and Cycles, for two",
    "archive": "games of the Chip8 Community Archive (CC0, shipped in the package): Octojam entries and "
               "others, CHIP-8, SUPER-CHIP and XO-CHIP",
}
_REGISTRY: dict[str, GameSpec] = {}
_SUITE_OF: dict[str, str] = {}


def register(spec: GameSpec, suite: str = "octax") -> None:
    """Adds a game to a suite; ids are unique (as in gymnax's registry)."""
    _check_suite(suite)
    if spec.id in _REGISTRY:
        raise ValueError(f"game {spec.id!r} is already registered")
    _REGISTRY[spec.id] = spec
    _SUITE_OF[spec.id] = suite


def _check_suite(suite: str) -> None:
    if suite not in SUITES:
        raise ValueError(f"unknown suite {suite!r}; valid suites: {', '.join(repr(s) for s in SUITES)}")


def _discover(package: str = __name__, path=__path__, suite: str = "octax") -> None:
    for module in sorted(pkgutil.iter_modules(path), key=lambda m: m.name):
        if module.name == "spec" or module.name.startswith("_"):
            continue
        games = importlib.import_module(f"{package}.{module.name}")
        if module.ispkg:
            _discover(games.__name__, games.__path__, games.SUITE)
            continue
        for spec in games.SPECS:
            register(spec, getattr(games, "SUITE", suite))


def list_games(suite: Optional[str] = None, players: Optional[int] = None) -> list[str]:
    """Ids of the registered games of `suite` (every suite when None), sorted.

    `players=None` or 1 lists the games one agent plays (`make`); `players=2` lists the two-player
    games (`make_multi`), which include two-player games that are not one-player envs too.

    Raises:
        ValueError: an unknown suite or player count; the message lists the valid ones.
    """
    if players not in (None, 1, 2):
        raise ValueError(f"players must be 1 or 2 (or None for 1), got {players!r}")
    if suite is not None:
        _check_suite(suite)
    def wanted(spec: GameSpec) -> bool:
        return spec.players == 2 if players == 2 else spec.solo
    return sorted(game for game, its_suite in _SUITE_OF.items()
                  if (suite is None or its_suite == suite) and wanted(_REGISTRY[game]))


def suite_of(game_id: str) -> str:
    """The suite a registered game belongs to (KeyError for an unknown id, as `get_spec`)."""
    get_spec(game_id)
    return _SUITE_OF[game_id]


def get_spec(game_id: str) -> GameSpec:
    """The `GameSpec` for `game_id`.

    Raises:
        KeyError: unknown id; the message lists the valid ones.
    """
    try:
        return _REGISTRY[game_id]
    except KeyError:
        raise KeyError(f"unknown game {game_id!r}; valid ids: {', '.join(sorted(_REGISTRY))}") from None


_discover()

__all__ = ["CATEGORIES", "GameSpec", "SUITES", "Seats", "bcd_value", "get_spec", "in_routine", "key_mask", "list_games", "ram_value", "register",
           "register_value", "suite_of"]
