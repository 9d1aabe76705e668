"""`octax_gym.pettingzoo`: PettingZoo's own API and seed tests on every two-player game, and the
turn order, rewards and errors worked by hand on tests/two_player_games.py's TakeTurns.

SpaceRacer (simultaneous) and TakeTurns (turn-based) run in the default selection; every other
game of `octax_core.list_games(players=2)` is covered by the same tests marked slow (each costs a
compile), so a game added to the registry is tested without an edit here.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pettingzoo")
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test, seed_test  # noqa: E402

import octax_core  # noqa: E402
from octax_gym import IllegalMoveError, InvalidActionError  # noqa: E402
from octax_gym import pettingzoo as octax_pz  # noqa: E402

from two_player_games import TAKE_TURNS  # noqa: E402

FAST = ("SpaceRacer",)
GAMES = ["TakeTurns", *FAST] + [pytest.param(game, marks=pytest.mark.slow)
                                for game in octax_core.list_games(players=2) if game not in FAST]
CYCLES = 100


@pytest.fixture(scope="module")
def turns_rom(take_turns_rom):
    return take_turns_rom


@pytest.fixture
def make(turns_rom):
    """make(kind, game, **kw): `octax_pz.parallel_env` or `octax_pz.env` ("TakeTurns" is the test game)."""
    def build(kind, game, **kw):
        constructor = octax_pz.parallel_env if kind == "parallel" else octax_pz.env
        if game == "TakeTurns":
            return constructor(TAKE_TURNS, rom=turns_rom, **kw)
        return constructor(game, **kw)
    return build


@pytest.mark.parametrize("game", GAMES)
def test_parallel_api(make, game):
    parallel_api_test(make("parallel", game), num_cycles=CYCLES)
    parallel_seed_test(lambda: make("parallel", game), num_cycles=CYCLES)


@pytest.mark.parametrize("game", GAMES)
def test_aec_api(make, game):
    api_test(make("aec", game), num_cycles=CYCLES)
    seed_test(lambda: make("aec", game), num_cycles=CYCLES)


def test_agents_and_spaces(make):
    env = make("parallel", "SpaceRacer")
    assert env.possible_agents == ["first_0", "second_0"] and env.agents == []
    box = env.observation_space("first_0")
    assert box.shape == (5, 32, 64) and box.dtype == np.uint8 and env.action_space("second_0").n == 3
    assert env.observation_space("first_0") is box and env.observation_space("second_0") is not box
    obs, infos = env.reset(seed=3)
    assert env.agents == ["first_0", "second_0"] and (obs["first_0"][-1] == 0).all() and (obs["second_0"][-1] == 1).all()
    assert infos["first_0"]["current_player"] == -1 and infos["second_0"]["action_mask"].tolist() == [1, 1, 1]
    obs, rewards, terminations, truncations, infos = env.step({"first_0": 1, "second_0": np.int64(2)})
    assert set(rewards) == set(terminations) == set(truncations) == set(infos) == {"first_0", "second_0"}
    assert isinstance(rewards["first_0"], float) and terminations == {"first_0": False, "second_0": False}
    assert infos["first_0"]["episode_step"] == 1
    assert env.state().shape == (4, 32, 64) and env.state() in env.state_space
    with pytest.raises(ValueError, match="no action for second_0"):
        env.step({"first_0": 1})
    with pytest.raises(ValueError, match="unknown agent"):
        env.step({"first_0": 1, "second_0": 0, "third_0": 0})
    with pytest.raises(InvalidActionError, match="seat second_0"):
        env.step({"first_0": 1, "second_0": 3})
    with pytest.raises(TypeError, match="fix"):
        octax_pz.parallel_env("SpaceRacer", backend="torch")


def test_render(make):
    env = make("parallel", "SpaceRacer", render_mode="rgb_array", render_scale=2)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (64, 128, 3) and frame.dtype == np.uint8
    env.close()


def test_aec_turns_follow_the_game(make):
    env = make("aec", "TakeTurns")
    env.reset(seed=0)
    space = env.observation_space("first_0")
    assert set(space.spaces) == {"observation", "action_mask"} and space["observation"].shape == (5, 32, 64)
    assert env.agent_selection == "first_0"
    assert env.observe("second_0")["action_mask"].tolist() == [1, 0]  # not its turn: no-op alone
    env.step(1)  # first_0 counts: its turn passes
    assert env.agent_selection == "second_0" and env.rewards == {"first_0": 1.0, "second_0": -1.0}
    env.step(0)  # second_0 waits: still its turn
    assert env.agent_selection == "second_0" and env.infos["second_0"]["episode_step"] == 2
    env.step(1)
    assert env.agent_selection == "first_0" and env.rewards == {"first_0": -1.0, "second_0": 1.0}
    assert env.last()[1] == 0.0  # first_0's reward since it last acted: +1 + 0 - 1
    with pytest.raises(ValueError, match="live"):
        env.step(None)
    for _ in range(3):  # 4 each; then first_0 reaches 5
        env.step(1)
        env.step(1)
    env.step(1)
    assert all(env.terminations.values()) and env.rewards == {"first_0": 1.0, "second_0": -1.0}
    while env.agents:
        env.step(None)


def test_aec_simultaneous_steps_once_both_have_acted(make):
    env = make("aec", "SpaceRacer")
    env.reset(seed=0)
    assert env.agent_selection == "first_0"
    env.step(1)
    assert env.agent_selection == "second_0" and env.infos["second_0"]["episode_step"] == 0
    env.step(2)
    assert env.agent_selection == "first_0" and env.infos["first_0"]["episode_step"] == 1


def test_parallel_turns(make):
    env = make("parallel", "TakeTurns")
    obs, infos = env.reset(seed=0)
    assert obs["second_0"]["action_mask"].tolist() == [1, 0] and infos["first_0"]["current_player"] == 0
    _, rewards, *_ = env.step({"first_0": 1, "second_0": 1})  # second_0's move is not its turn: ignored
    assert rewards == {"first_0": 1.0, "second_0": -1.0}
    _, rewards, *_ = env.step({"second_0": 1})  # the agent not to move may be left out
    assert rewards == {"first_0": -1.0, "second_0": 1.0}
    strict = make("parallel", "TakeTurns", off_turn="raise")
    strict.reset(seed=0)
    with pytest.raises(IllegalMoveError, match="second_0 \\(env 0\\) played action 1, but it is first_0's turn"):
        strict.step({"first_0": 1, "second_0": 1})
    with pytest.raises(octax_pz.UnknownOptionError if hasattr(octax_pz, "UnknownOptionError") else ValueError):
        make("parallel", "TakeTurns", off_turn="maybe")
