"""The names a game goes by, and the one resolver from what a user types to a registered game.

A game has a registry id ("Pong", "BlackRainbow" for an archive game) and a Gymnasium id
("octax/Pong-v0"). Every place that takes a game by name (the envs, `video.record`,
`collect_dataset`, the `octax-gym` commands) resolves it here, so each accepts the same
spellings: either id, exactly or in any case. An unknown name raises one error,
`UnknownOptionError` (a ValueError and a KeyError), naming the close matches and every id. The
close matches are the core's (`octax_core.env.games.close_names`, behind `octax_core.make`'s
`UnknownGameError` too), so both layers suggest the same games.
"""

from __future__ import annotations

from typing import Union

from octax_core.env.games import GameSpec, close_names, get_spec, list_games
from octax_gym.envs.choices import UnknownOptionError

NAMESPACE = "octax"


def env_id(game: Union[str, GameSpec]) -> str:
    """The Gymnasium id of a registered game id or of a `GameSpec`, e.g. "Pong" -> "octax/Pong-v0",
    "Duel-v1" -> "octax/Duel-v1" (`GameSpec.base_id`)."""
    spec = game if isinstance(game, GameSpec) else get_spec(game)
    return f"{NAMESPACE}/{spec.base_id}-v{spec.version}"


def resolve_spec(game: Union[str, GameSpec], players: int = 1) -> GameSpec:
    """The registered game a name means: its id or Gymnasium id, exact first, then in any case.

    Every registered game resolves, the two-player games that are not one-player envs too (a
    one-player env of one refuses it by name: it needs an opponent). A `GameSpec` is taken as it
    is (your own game, `register_game`).

    Raises:
        TypeError: neither a str nor a GameSpec.
        UnknownOptionError: no game goes by that name; the message lists every id (with
            `players=2`, every two-player id).
    """
    if isinstance(game, GameSpec):
        return game
    if not isinstance(game, str):
        raise TypeError(f"game must be a registered id (str) or a GameSpec, got {type(game).__name__}")
    names = _names()
    found = names.get(game) or {name.lower(): game_id for name, game_id in names.items()}.get(game.lower())
    if found is None:
        games = list_games(players=players)
        also = f"or their Gymnasium ids ({env_id(games[0])}, ...)" if games else ""
        raise UnknownOptionError("game" if players == 1 else "two-player game", game, games, also,
                                 near=close_names(game, names))
    return get_spec(found)


def resolve_env_id(game: Union[str, GameSpec]) -> str:
    """The Gymnasium id of the game a name means: "Pong", "pong" and "octax/Pong-v0" all give
    "octax/Pong-v0".

    Raises:
        TypeError, UnknownOptionError: as `resolve_spec`.
    """
    return env_id(resolve_spec(game))


def _names() -> dict[str, str]:
    """Every accepted exact name -> the registry id (read per call: games may be registered late)."""
    games = sorted(set(list_games()) | set(list_games(players=2)))
    return {game: game for game in games} | {env_id(game): game for game in games}
