"""`octax/Mix-v0`: many games in one batch through Gymnasium (`OctaxVectorEnv(games=...)`), torch
by DLPack, and SB3 on it unchanged."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch

import octax_gym
from octax_gym import MIX_ENV_ID, OctaxVectorEnv

GAMES = ["Pong", "Brix", "Tetris"]  # 2, 2 and 4 keys: the mix has 5 actions


@pytest.fixture(scope="module")
def envs():
    """Four envs in SAME_STEP with obs_scale=255: the compiled step of the SB3 run below (what SB3
    fixes), so the two tests share it; the mode and the scale change nothing checked here."""
    envs = gym.make_vec(MIX_ENV_ID, num_envs=4, games=GAMES, autoreset_mode="same_step", obs_scale=255)
    yield envs
    envs.close()


def test_mix_v0_steps_a_batch_of_different_games(envs):
    assert MIX_ENV_ID == "octax/Mix-v0" and MIX_ENV_ID in gym.registry
    obs, info = envs.reset(seed=0)
    assert obs.shape == (4, 4, 32, 64) and envs.single_action_space == gym.spaces.Discrete(5)
    assert info["game"].shape == (4,) and set(info["game"].tolist()) <= {0, 1, 2}
    assert info["action_mask"].shape == (4, 5)
    np.testing.assert_array_equal(info["action_mask"].sum(axis=1), np.array([3, 3, 5])[info["game"]])
    for _ in range(3):
        obs, reward, terminated, truncated, info = envs.step(envs.action_space.sample())
    assert reward.shape == (4,) and reward.dtype == np.float32 and "_game" in info
    assert repr(envs.unwrapped).startswith("OctaxVectorEnv(mix(Pong, Brix, Tetris), num_envs=4")


def test_a_row_of_a_one_game_mix_plays_as_gym_make_seeded_s_plus_i():
    """Weights that only draw Brix: row i of the mix seeded s is gym.make("octax/Brix-v0") seeded s + i."""
    mix = OctaxVectorEnv(GAMES, 3, weights=[0, 1, 0], autoreset_mode="disabled")
    single = gym.make("octax/Brix-v0")
    mix_obs, mix_info = mix.reset(seed=10)
    assert (mix_info["game"] == 1).all()
    rng = np.random.default_rng(0)
    actions = rng.integers(0, 3, (12, 3))
    rows = [mix.step(a) for a in actions]
    for i in range(3):
        obs, _ = single.reset(seed=10 + i)
        np.testing.assert_array_equal(obs, mix_obs[i])
        for t, a in enumerate(actions[:, i]):
            obs, reward, terminated, truncated, info = single.step(int(a))
            np.testing.assert_array_equal(obs, rows[t][0][i])
            assert reward == rows[t][1][i] and terminated == rows[t][2][i] and info["score"] == rows[t][4]["score"][i]


def test_torch_backend_and_named_mix():
    envs = OctaxVectorEnv("octax16", 16, backend="torch")
    obs, info = envs.reset(seed=1)
    assert isinstance(obs, torch.Tensor) and obs.shape == (16, 4, 32, 64) and obs.dtype == torch.uint8
    assert envs.core_env.num_games == 16 and envs.single_action_space.n == 6
    obs, *_ = envs.step(torch.zeros(16, dtype=torch.int64))
    assert isinstance(obs, torch.Tensor)


def test_bad_mixes_are_named_errors():
    with pytest.raises(ValueError, match="weights= is for a mix of games"):
        OctaxVectorEnv("Pong", 2, weights=[1])
    with pytest.raises(ValueError, match=r"one platform, got several \(chip8: Pong; schip: Rockto\)"):
        OctaxVectorEnv(["Pong", "Rockto"], 2)
    with pytest.raises(octax_gym.UnknownOptionError, match="unknown game 'Pongg'"):
        OctaxVectorEnv(["Pongg"], 2)
    with pytest.raises(ValueError, match="non-empty list of games"):
        OctaxVectorEnv([], 2)
    with pytest.raises(ValueError, match="no opponent= or rom="):
        OctaxVectorEnv(GAMES, 2, opponent="random")
    with pytest.raises(ValueError, match=r"weights must be one number per game \(3\)"):
        OctaxVectorEnv(GAMES, 2, weights=[1, 2])


def test_sb3_ppo_trains_on_a_mix_unchanged():
    from stable_baselines3 import PPO
    from octax_gym.sb3 import make_sb3_vec_env, ppo_kwargs

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        venv = make_sb3_vec_env(MIX_ENV_ID, 4, games=GAMES)
        model = PPO("CnnPolicy", venv, **{**ppo_kwargs(4), "n_steps": 16, "batch_size": 32, "n_epochs": 1}, seed=0)
        model.learn(64)
        assert model.num_timesteps == 64 and model.action_space.n == 5
        venv.close()
    finally:
        torch.set_num_threads(threads)
