"""The game registry: every module in this package exports `SPECS`, a tuple of `GameSpec`.

Modules are discovered, not listed, so adding a game is adding one module. Lookups raise errors
that name the valid ids.
"""

from __future__ import annotations

import importlib
import pkgutil

from octax_core.env.games.spec import CATEGORIES, GameSpec, key_mask

_REGISTRY: dict[str, GameSpec] = {}


def register(spec: GameSpec) -> None:
    """Adds a game; ids are unique (as in gymnax's registry)."""
    if spec.id in _REGISTRY:
        raise ValueError(f"game {spec.id!r} is already registered")
    _REGISTRY[spec.id] = spec


def _discover() -> None:
    for module in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if module.name == "spec" or module.name.startswith("_"):
            continue
        for spec in importlib.import_module(f"{__name__}.{module.name}").SPECS:
            register(spec)


def list_games() -> list[str]:
    """Ids of every registered game, sorted."""
    return sorted(_REGISTRY)


def get_spec(game_id: str) -> GameSpec:
    """The `GameSpec` for `game_id`.

    Raises:
        KeyError: unknown id; the message lists the valid ones.
    """
    try:
        return _REGISTRY[game_id]
    except KeyError:
        raise KeyError(f"unknown game {game_id!r}; valid ids: {', '.join(list_games())}") from None


_discover()

__all__ = ["CATEGORIES", "GameSpec", "get_spec", "key_mask", "list_games", "register"]
