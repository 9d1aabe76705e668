"""The game registry: every module in this package exports `SPECS`, a tuple of `GameSpec`.

Modules are discovered, not listed, so adding a game is adding one module. A module may name its
suite (`SUITE = "ours"`); without one its games are the octax paper's. A subpackage holds a suite
of its own (`archive/`: the Chip8 Community Archive's games): its `__init__` names the suite, and
its modules are discovered the same way. A lookup of an unknown id raises `UnknownGameError`,
naming the close matches ("did you mean 'Pong'?") rather than listing every id; an unknown suite
lists the suites.
"""

from __future__ import annotations

import difflib
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
MAX_SUGGESTIONS = 3  # close matches an unknown name's error names


class UnknownGameError(KeyError, ValueError):
    """No registered game has this id. The message names the close matches and where the
    valid ids are listed, not the ids themselves: with the archive that list is a page long,
    and the near miss is what a typo needs.

    A KeyError, what a registry lookup raised before, and a ValueError, as the Gymnasium
    layer's error for an unknown name (`octax_gym.UnknownOptionError`) is, so code catching
    either keeps working.

    Attributes:
        game: the name given.
        suggestions: the registered ids closest to it (at most `MAX_SUGGESTIONS`), best first.
    """

    def __init__(self, game, suggestions: tuple[str, ...] = ()):
        self.game, self.suggestions = game, tuple(suggestions)
        hint = f"; did you mean {' or '.join(map(repr, self.suggestions))}?" if self.suggestions else ""
        super().__init__(f"unknown game {game!r}{hint} (see octax_core.list_games(), and "
                         f"list_games(players=2) for the two-player games)")

    def __str__(self) -> str:
        return ValueError.__str__(self)  # not KeyError's, which would print the message as a repr


def close_names(name, names, limit: int = MAX_SUGGESTIONS) -> list[str]:
    """The `names` closest to `name`, best first, compared in any case ("pong" and "Pongg" both
    give "Pong"); [] when none is close or `name` is not a str. Every layer's unknown-game error
    suggests from this one function, so they name the same games."""
    if not isinstance(name, str):
        return []
    lowered: dict[str, str] = {}
    for candidate in names:
        lowered.setdefault(candidate.lower(), candidate)
    return [lowered[match] for match in difflib.get_close_matches(name.lower(), list(lowered), n=limit, cutoff=0.75)]


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
    """The suite a registered game belongs to (`UnknownGameError` for an unknown id, as `get_spec`)."""
    get_spec(game_id)
    return _SUITE_OF[game_id]


def get_spec(game_id: str) -> GameSpec:
    """The `GameSpec` for `game_id`.

    Raises:
        UnknownGameError (a KeyError and a ValueError): no game has this id; the message names
            the close matches.
    """
    try:
        return _REGISTRY[game_id]
    except (KeyError, TypeError):  # TypeError: an unhashable id
        raise UnknownGameError(game_id, close_names(game_id, _REGISTRY)) from None


_discover()

__all__ = ["CATEGORIES", "GameSpec", "SUITES", "Seats", "UnknownGameError", "bcd_value", "close_names", "get_spec",
           "in_routine", "key_mask", "list_games", "ram_value", "register", "register_value", "suite_of"]
