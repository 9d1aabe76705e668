"""The PettingZoo envs as their users expect (issue 39): each agent's `lives` is its own seat's,
and each agent's `action_mask` is what `action_space(agent).sample(mask=...)` takes, as in the
Gymnasium views (tests/gym_layer/test_newcomer_gym.py). Worked on tests/two_player_games.py's
TakeTurns, given a lives count for player 1 (a small compile)."""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np
import pytest

pytest.importorskip("pettingzoo")
from octax_gym import pettingzoo as octax_pz  # noqa: E402

from two_player_games import TAKE_TURNS, TURNS_GOAL  # noqa: E402

# Player 1's lives, as a one-player spec counts them (Duel's and Cycles' `lives_fn` are so): the
# rounds player 2 still needs to win.
WITH_LIVES = dataclasses.replace(TAKE_TURNS, lives_fn=lambda s: TURNS_GOAL - s.V[1].astype(jnp.int32))


@pytest.fixture(scope="module")
def rom(take_turns_rom):
    return take_turns_rom


def test_lives_are_per_seat_and_a_seat_without_a_count_says_so(rom):
    env = octax_pz.parallel_env(WITH_LIVES, rom=rom)
    _, infos = env.reset(seed=0)
    assert infos["first_0"]["lives"] == TURNS_GOAL  # player 1's count, the spec's `lives_fn`
    assert infos["second_0"]["lives"] == -1  # the game counts none for player 2: not player 1's count
    _, _, _, _, infos = env.step({"first_0": 0, "second_0": 0})
    assert [infos[agent]["lives"] for agent in env.possible_agents] == [TURNS_GOAL, -1]
    env.close()
    _, infos = octax_pz.parallel_env(TAKE_TURNS, rom=rom).reset(seed=0)  # no `lives_fn`: -1 for both
    assert [infos[agent]["lives"] for agent in ("first_0", "second_0")] == [-1, -1]


@pytest.mark.parametrize("kind", ["parallel", "aec"])
def test_every_agent_s_mask_samples_its_legal_actions(rom, kind):
    env = (octax_pz.parallel_env if kind == "parallel" else octax_pz.env)(TAKE_TURNS, rom=rom)
    if kind == "parallel":
        _, infos = env.reset(seed=0)
    else:
        env.reset(seed=0)
        infos = env.infos
    for agent in env.possible_agents:
        mask = infos[agent]["action_mask"]
        assert mask.dtype == np.int8
        action = env.action_space(agent).sample(mask=mask)
        assert mask[action] == 1
    assert infos["second_0"]["action_mask"].tolist() == [1, 0]  # seat 0 moves first: no-op alone
    env.close()


@pytest.mark.parametrize("seat", [0, 1])
def test_the_one_seat_view_reports_its_own_seat_s_lives(rom, seat):
    """The Gymnasium view of one seat against an opponent says the same as PettingZoo's agent of
    that seat: player 1's count on seat 0, NO_LIVES (-1) on seat 1, never the opponent's count."""
    from octax_gym.envs.env import OctaxEnv

    env = OctaxEnv(WITH_LIVES, rom=rom, opponent="noop", seat=seat)
    _, info = env.reset(seed=0)
    assert int(info["lives"]) == (TURNS_GOAL if seat == 0 else -1)
    _, _, _, _, info = env.step(0)
    assert int(info["lives"]) == (TURNS_GOAL if seat == 0 else -1)
    env.close()
