"""One table of players (octax_core/env/players.py) read by every layer that plays a seat by
itself: the policies of one-player envs, the tracer, the opponents of the one-seat view and the
web player's seats; and the table's "eps<p>" players as opponents, worked on
tests/two_player_games.py's TwoCounters (the scripted player holds its second key: +8 a step)."""

from __future__ import annotations

import numpy as np
import pytest

from octax_core.env import players
from octax_core.tools import trace
from octax_gym import OctaxEnv, OctaxVectorEnv, opponent, policies
from octax_gym.play import protocol

from two_player_games import TWO_COUNTERS


def test_every_layer_names_the_one_table():
    assert tuple(policies.POLICIES) == trace.POLICIES == players.SEATLESS == ("random", "noop")
    assert opponent.OPPONENTS == tuple(players.PLAYERS) == ("random", "noop", "scripted")
    assert set(protocol.TABLE_PLAYERS) <= set(players.PLAYERS)


def _opponent_counters(name, rom, steps=3) -> list[int]:
    """The opponent's counter after `steps` in 8 games (seeds 5..12) of one single env (its
    compiled step, one per opponent, is test_opponent's: "scripted" there too)."""
    env = OctaxEnv(TWO_COUNTERS, rom=rom, opponent=name)
    counters = []
    for seed in range(5, 13):
        env.reset(seed=seed)
        for _ in range(steps):
            env.step(0)  # the learner (seat 0) holds nothing
        counters.append(int(env.state.machine.V[0, 1]))  # the opponent's counter
    return counters


def test_the_ladders_players_are_opponents_too(two_counters_rom):
    assert _opponent_counters("eps0", two_counters_rom) == _opponent_counters("scripted", two_counters_rom) == [24] * 8
    diluted = _opponent_counters("eps1", two_counters_rom)  # uniform: 0, 4 or 8 a step
    assert min(diluted) < 24 and all(c % 4 == 0 for c in diluted)
    with pytest.raises(ValueError, match=r"eps of 'eps2' must be a number in \[0, 1\]"):
        OctaxVectorEnv(TWO_COUNTERS, 2, rom=two_counters_rom, opponent="eps2")
    with pytest.raises(ValueError, match="SpaceRacer has no scripted policy.*no 'eps0.5'"):
        OctaxVectorEnv("SpaceRacer", 2, opponent="eps0.5")
