"""OctaxEnv, the env behind gymnasium.make: Gymnasium's checker, rendering, episodes."""

from __future__ import annotations

import gymnasium as gym
import pytest
from gymnasium.utils.env_checker import check_env

import octax_gym  # noqa: F401  (registers the ids)
from counter_game import COUNTER
from octax_gym import OctaxEnv


def test_gymnasium_check_env_with_render_on_a_real_game():
    env = gym.make("octax/Brix-v0", render_mode="rgb_array")
    check_env(env.unwrapped)  # raises on any failure, including the render checks
    assert env.unwrapped.render().shape == (256, 512, 3)


@pytest.mark.filterwarnings("ignore:.*not having a spec")  # no registered id, so no other modes to try
def test_gymnasium_check_env_on_counter(counter_rom):
    check_env(OctaxEnv(COUNTER, rom=counter_rom, render_mode="rgb_array", obs_scale=255, render_scale=2))


def test_check_env_catches_a_nondeterministic_env(counter_rom, monkeypatch):
    """The checker above is a real check: break reset determinism and it fails."""
    env = OctaxEnv(COUNTER, rom=counter_rom, render_mode="rgb_array")
    reset = env.reset
    calls = iter(range(100))
    monkeypatch.setattr(env, "reset", lambda seed=None, options=None: reset(seed=None if seed is None else seed + next(calls), options=options))
    with pytest.raises(AssertionError):
        check_env(env)


def test_an_episode_ends_and_reset_starts_another(counter_rom):
    env = OctaxEnv(COUNTER, rom=counter_rom)
    env.reset(seed=1)
    rewards = []
    for _ in range(3):
        obs, reward, terminated, truncated, info = env.step(2)
        rewards.append(reward)
    assert rewards == [8.0, 8.0, 8.0] and terminated and not truncated and info["lives"] == 0
    # Steps after the end stand still until reset (the env checker warns about them, too).
    assert env.step(2)[1:4] == (0.0, True, False)
    obs, info = env.reset()
    assert info == {"score": 0.0, "lives": 24, "episode_step": 0}
    assert env.step(1)[1] == 4.0


def test_render_fps_follows_frames_per_step(counter_rom):
    assert OctaxEnv(COUNTER, rom=counter_rom).metadata["render_fps"] == 15
    assert OctaxEnv(COUNTER, rom=counter_rom, frames_per_step=2).metadata["render_fps"] == 30


def test_render_without_mode_warns_and_returns_none(counter_rom):
    env = OctaxEnv(COUNTER, rom=counter_rom)
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None
