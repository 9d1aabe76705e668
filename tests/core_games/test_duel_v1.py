"""Duel-v1 (roms/duel_v1.8o): Duel's version with a ball three times as fast, drawn in every
frame, registered beside Duel (v0, unchanged) as "Duel-v1" / octax/Duel-v1. Its point: the
scripted player, which never concedes in Duel, concedes points to itself here."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.env.games import duel, get_spec
from octax_core.env.games.spec import GameSpec
from octax_core.env.ladder import make_match, record
from octax_core.env.players import make_player

GAMES = 32
SERVE_X = 31


def test_v1_is_registered_beside_v0():
    v0, v1 = get_spec("Duel"), get_spec("Duel-v1")
    assert (v0.version, v0.rom_file, v0.solo) == (0, "duel.ch8", True)
    assert (v1.version, v1.rom_file, v1.solo, v1.base_id) == (1, "duel_v1.ch8", False, "Duel")
    assert "Duel-v1" in octax_core.list_games(players=2) and "Duel-v1" not in octax_core.list_games()
    with pytest.raises(ValueError, match="an id ending in -v2 names that version; its version is 1"):
        GameSpec(**{**{f: getattr(v1, f) for f in ("title", "rom_file", "rom_sha1", "action_keys", "score_fn",
                                                    "terminated_fn", "category", "description")},
                    "id": "Duel-v2", "version": 1})


def _ball_xs(game: str, frames: int = 60):
    """The ball's x after each frame of one game of scripted players, from the first serve on."""
    env, params = octax_core.make_multi(game, frames_per_step=1)
    _, state = env.reset(jax.random.key(0), params)
    step = jax.jit(env.step)
    bots = jax.jit(lambda machine: jnp.stack([env.seats.scripted_policy(machine, seat) for seat in (0, 1)]))
    xs = []
    for t in range(frames + 80):
        _, state, *_ = step(jax.random.key(t), state, bots(state.machine), params)
        if int(state.machine.V[duel.BALL_DX]):  # served
            xs.append(int(state.machine.V[duel.BALL_X]))
    return np.array(xs[:frames])


def test_the_ball_moves_6_pixels_a_move_and_stops_at_a_face():
    xs = _ball_xs("Duel-v1", 200)
    in_play = xs[1:] != SERVE_X  # a point sends the ball back to the centre
    assert set(np.abs(np.diff(xs))[in_play].tolist()) == {0, 2, 4, 6}  # 6 a move; 4 or 2 to a face (from 7, 57)
    assert {3, 59} <= set(xs.tolist()) <= set(range(3, 60))
    assert set(np.abs(np.diff(_ball_xs("Duel"))).tolist()) == {0, 2}


def _frames_with_a_ball(game: str, steps: int = 300, envs: int = 8) -> float:
    """Of random play's frames, the share that show the ball: a lit pixel between the paddles'
    columns, outside the scores' rows."""
    env, params = octax_core.make_multi(game)
    keys = jax.random.split(jax.random.key(1), envs)
    obs, state = jax.vmap(env.reset, in_axes=(0, None))(keys, params)

    def body(carry, t):
        obs, state = carry
        actions = jax.random.randint(jax.random.fold_in(jax.random.key(2), t), (envs, 2), 0, env.num_actions)
        obs, state, *_ = jax.vmap(env.step, in_axes=(0, 0, 0, None))(keys, state, actions, params)
        frames = obs[:, 0, :-1, 7:, 3:61]  # below the scores (rows 1..5), between the paddles
        return (obs, state), (frames > 0).any((-1, -2))

    _, seen = jax.lax.scan(jax.jit(body), (obs, state), jnp.arange(steps))
    return float(np.asarray(seen).mean())


def test_the_ball_is_drawn_in_every_frame():
    # v1 lacks it only while it flies through the scores' rows; v0 shows it in about 1 frame of 4
    assert _frames_with_a_ball("Duel-v1") > 0.85 > 0.4 > _frames_with_a_ball("Duel")


def test_the_scripted_player_concedes_points_to_itself():
    env, params = octax_core.make_multi("Duel-v1")
    # one compiled match plays both pairings (the players are chosen by index, as data)
    match = make_match(env, params, GAMES, 1500, [make_player("scripted", env.spec), make_player("random", env.spec)])
    result = record(match(0, None, 0, None, jax.random.key(0)))  # scripted against itself
    assert result["win"] + result["loss"] >= 0.25  # v0: no point in 2,000 steps, every game a 0-0 draw
    assert record(match(0, None, 1, None, jax.random.key(1)))["win"] == 1.0  # scripted against random
