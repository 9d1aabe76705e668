"""Duel-v1 in the Gymnasium layer: its id is octax/Duel-v1 (the spec's id "Duel-v1" is its
name and version), beside octax/Duel-v0; a two-player-only game, it is one seat against an
opponent."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import octax_gym
from octax_gym import OpponentRequiredError
from octax_gym.envs.game_names import resolve_spec


def test_duel_v1_is_octax_duel_v1_beside_v0():
    assert octax_gym.env_id("Duel-v1") == "octax/Duel-v1" and octax_gym.env_id("Duel") == "octax/Duel-v0"
    assert resolve_spec("octax/Duel-v1", players=2).version == 1 and resolve_spec("octax/Duel-v0").version == 0
    with pytest.raises(OpponentRequiredError, match=r"gymnasium.make\('octax/Duel-v1', opponent='random'\)"):
        gym.make("octax/Duel-v1")
    env = gym.make("octax/Duel-v1", opponent="scripted", seat=1)
    obs, info = env.reset(seed=0)
    assert obs.shape == (5, 32, 64) and (obs[-1] > 0).all()  # the player plane of seat 1
    obs, reward, terminated, truncated, info = env.step(np.int64(0))
    assert reward == 0 and not terminated  # the first serve is still waiting
    env.close()
