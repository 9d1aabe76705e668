"""What our own Octo games with levels (roms/*.8o: Dodge, Flak, Cycles) share: one register map,
one start-up, levels.

They keep the score in V5 (Cycles: player 1's rounds) and the lives in V6 (Cycles: player 2's
rounds), set VE = 1 at game over, and pick their level on a start screen with key 1, 2 or 3, so
each level is its own env: `<Name>1`..`<Name>3`, plus `<Name>` for the default level. A game module gives its level table and its own fields; this
module makes the specs. (A leading underscore keeps the registry from reading it as a game.)
"""

from __future__ import annotations

from typing import Callable, Sequence

from octax_core.env.games.spec import GameSpec, key_mask, register_value

SCORE, LIVES, GAME_OVER = 5, 6, 14  # V5, V6, VE


def own_game_spec(game_id: str, level: int, **fields) -> GameSpec:
    """A spec with our games' shared parts; `fields` give the rest (title, ROM, keys, ...) and
    may replace a shared part (Cycles keeps no lives: its `lives_fn` is its own).

    Start-up: 10 frames (the start screen drawn), the level's key held 3 frames, 25 frames: the
    play screen drawn, inside the 48-frame pause before play, so the first random draws of an
    episode come from its reset key.
    """
    shared = dict(
        score_fn=lambda state: register_value(state, SCORE),
        terminated_fn=lambda state: state.V[GAME_OVER] == 1,
        lives_fn=lambda state: register_value(state, LIVES),
        startup=((0, 10), (key_mask(level), 3), (0, 25)),
        quirks="chip8",
        max_episode_steps=4500,
    )
    return GameSpec(id=game_id, **{**shared, **fields})


def level_specs(name: str, levels: Sequence[tuple], default: int,
                make_spec: Callable[..., GameSpec]) -> tuple[GameSpec, ...]:
    """`<name><level>` for each row of `levels`, then `<name>` for the `default` level.

    Each row is (level, *details); `make_spec(game_id, level, *details)` builds its spec.
    """
    rows = {row[0]: row for row in levels}
    return tuple(make_spec(f"{name}{row[0]}", *row) for row in levels) + (make_spec(name, *rows[default]),)
