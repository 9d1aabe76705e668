"""The opponent ladder (octax_core/env/ladder.py): the compiled match's seats, the Bradley-Terry
Elo, and a ladder played on tests/two_player_games.py's TwoCounters (each seat's first key scores
it 4 a step, its second 8; the first to 24 ends the game; the scripted player holds the second)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.env.ladder import (RUNGS, bradley_terry_elo, elo_against, ladder_players, make_match, play_ladder,
                                   record, rungs)
from octax_core.env.games import get_spec

from two_player_games import GOAL, TWO_COUNTERS


def only_on_seat_0(params, key, obs, state, seat, legal):
    """Holds its first key on seat 0 and nothing on seat 1: wins from seat 0 only."""
    return jnp.where(seat == 0, 1, 0)


def params_scale(params, key, obs, state, seat, legal):
    """Holds the key its params name: a network's params reach the match as an argument."""
    return params["action"]


GAMES = 32
NETWORK, SEAT_0 = 0, 1 + len(RUNGS)  # the players' indices: params_scale, the rungs, only_on_seat_0
NOTHING, FIRST, SECOND = ({"action": jnp.int32(a)} for a in range(3))


@pytest.fixture(scope="module")
def counters(two_counters_rom):
    """One match compiled for every test: params_scale first (play_ladder's agent), the rungs, then
    only_on_seat_0."""
    env, params = octax_core.make_multi(TWO_COUNTERS, rom=two_counters_rom)
    players = [params_scale, *ladder_players(TWO_COUNTERS), only_on_seat_0]
    return env, params, make_match(env, params, GAMES, 20, players)


def test_a_plays_seat_0_in_the_first_half_and_seat_1_in_the_second(counters):
    env, params, match = counters
    half = GAMES // 2
    result = match(SEAT_0, NOTHING, NETWORK, NOTHING, jax.random.key(0))  # vs a player holding nothing
    np.testing.assert_array_equal(result.return_a, [GOAL] * half + [0] * half)
    np.testing.assert_array_equal(result.return_b, [0] * GAMES)
    np.testing.assert_array_equal(result.ended, [True] * half + [False] * half)  # 20 steps of nothing: cut
    swapped = match(NETWORK, NOTHING, SEAT_0, NOTHING, jax.random.key(0))  # B on seat 0 in the second half
    np.testing.assert_array_equal(swapped.return_b, [0] * half + [GOAL] * half)
    assert record(result) == {"win": 0.5, "draw": 0.5, "loss": 0.0, "margin": GOAL / 2, "ended": 0.5,
                              "episodes": GAMES,
                              "by_seat": [{"win": 1.0, "draw": 0.0, "loss": 0.0, "margin": GOAL},
                                          {"win": 0.0, "draw": 1.0, "loss": 0.0, "margin": 0.0}]}


def test_params_are_an_argument_not_a_constant(counters):
    env, params, match = counters
    slow = match(NETWORK, FIRST, NETWORK, SECOND, jax.random.key(0))  # one key scores 4 a step, the other 8
    assert (slow.return_b > slow.return_a).all()
    fast = match(NETWORK, SECOND, NETWORK, FIRST, jax.random.key(0))
    assert (fast.return_a > fast.return_b).all()


def test_match_refuses_what_it_cannot_play(counters, two_counters_rom):
    env, params, match = counters
    autoreset, _ = octax_core.make_multi(TWO_COUNTERS, rom=two_counters_rom, autoreset=True)
    with pytest.raises(ValueError, match="autoreset=False"):
        make_match(autoreset, params, 8, 20, [only_on_seat_0])
    with pytest.raises(ValueError, match="num_games must be even"):
        make_match(env, params, 7, 20, [only_on_seat_0])
    with pytest.raises(ValueError, match=r"index_b must be an int in 0..6, got 7"):
        match(0, NOTHING, 7, NOTHING, jax.random.key(0))


def _expected_points(elo, games):
    gap = elo[None, :] - elo[:, None]
    points = games / (1 + 10 ** (gap / 400))
    np.fill_diagonal(points, 0)
    return points


def test_the_elo_fit_orders_a_known_ladder():
    truth = np.array([0.0, 150.0, 300.0, 500.0, 800.0])
    games = np.full((5, 5), 4000.0)
    np.fill_diagonal(games, 0)
    elo = bradley_terry_elo(_expected_points(truth, games), games, anchor=0)
    assert elo[0] == 0 and (np.diff(elo) > 0).all()
    np.testing.assert_allclose(elo, truth, atol=3)  # the virtual draws pull a little towards the middle
    # one player against the pool held fixed: its games alone, rated on the pool's scale
    against = 1 / (1 + 10 ** ((truth - 400.0) / 400))
    assert abs(elo_against(truth, against * 4000, np.full(5, 4000.0)) - 400) < 2
    # a perfect record stays finite (the virtual draw), above the best rung
    assert 800 < elo_against(truth, np.full(5, 64.0), np.full(5, 64.0)) < 2000
    with pytest.raises(ValueError, match="between 0 and the games"):
        bradley_terry_elo(games + 1, games, anchor=0)


def test_the_ladder_of_a_game_and_the_agents_elo(counters):
    env, params, match = counters
    assert rungs(get_spec("Cycles")) == RUNGS and rungs(get_spec("SpaceRacer")) == ("noop", "random")
    # the agent holds its second key: the scripted player's play, as a network with those params
    table = play_ladder(env, params, params_scale, SECOND, jax.random.key(1), num_games=GAMES, max_steps=20,
                        match=match)
    assert [row["opponent"] for row in table["rungs"]] == list(RUNGS)
    assert set(table["rungs"][0]) == {"opponent", "win", "draw", "loss", "margin", "ended", "episodes", "by_seat"}
    ladder = table["ladder"]
    assert ladder["random"] == 0 and ladder["scripted"] > ladder["eps0.5"] > ladder["random"]
    assert table["rungs"][0]["win"] > 0.9 and table["rungs"][-1]["draw"] == 1.0  # scripted vs itself: a tie
    assert table["elo"] > ladder["eps0.5"]
    with pytest.raises(ValueError, match="unknown player 'champion'"):
        play_ladder(env, params, params_scale, SECOND, jax.random.key(1), num_games=GAMES, max_steps=20,
                    opponents=["champion"], match=match)
