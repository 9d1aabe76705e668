"""Bad arguments and bad actions raise errors that name what was expected; nothing is clamped."""

from __future__ import annotations

import gymnasium as gym
import jax.numpy as jnp
import numpy as np
import pytest

import octax_gym  # noqa: F401
from counter_game import COUNTER
from octax_gym import InvalidActionError, OctaxEnv, OctaxVectorEnv
from octax_gym.envs.choices import UnknownOptionError


@pytest.fixture(scope="module")
def envs(counter_rom):
    envs = OctaxVectorEnv(COUNTER, 3, rom=counter_rom)
    envs.reset(seed=0)
    return envs


@pytest.mark.parametrize("kwargs, error, message", [
    (dict(num_envs=0), ValueError, "num_envs must be an int >= 1"),
    (dict(num_envs=2.5), ValueError, "num_envs must be an int >= 1"),
    (dict(backend="tensorflow"), UnknownOptionError, "unknown backend 'tensorflow'; valid: 'numpy', 'jax', 'torch'"),
    (dict(autoreset_mode="sometimes"), UnknownOptionError,
     r"valid: 'next_step', 'same_step', 'disabled', or an AutoresetMode \(AutoresetMode.NEXT_STEP"),
    (dict(render_mode="human"), UnknownOptionError, "unknown render_mode 'human'; valid: None, 'rgb_array'"),
    (dict(render_scale=0), ValueError, "render_scale must be an int in 1..64"),
    (dict(palette="purple"), UnknownOptionError, "valid: 'white', 'octo', 'green', 'amber', 'blue', or an"),
    (dict(palette=[(0, 0, 0), (0, 0, 300)]), ValueError, "pair of RGB triples"),
    (dict(obs_scale=2), ValueError, "obs_scale must be one of 1, 255, got 2"),
    (dict(frames_per_step=0), ValueError, "frames_per_step must be an int >= 1"),
    (dict(instructions_per_frame=-3), ValueError, "instructions_per_frame must be an int >= 1"),
    (dict(max_episode_steps=0), ValueError, "max_episode_steps must be an int >= 1"),
    (dict(repeat_action_probability=1.5), ValueError, r"repeat_action_probability must be a number in \[0, 1\]"),
    (dict(noop_max=-1), ValueError, "noop_max must be an int >= 0"),
    (dict(device="quantum"), UnknownOptionError, "unknown or unavailable device 'quantum'; valid: 'cpu:0'"),
    (dict(frame_skip=4), TypeError, r"unknown keyword\(s\) \['frame_skip'\]; valid: autoreset_mode"),
])
def test_bad_vector_env_arguments(counter_rom, kwargs, error, message):
    num_envs = kwargs.pop("num_envs", 2)
    with pytest.raises(error, match=message):
        OctaxVectorEnv(COUNTER, num_envs, rom=counter_rom, **kwargs)


def test_unknown_game_lists_the_valid_ids():
    with pytest.raises(KeyError, match="Pong"):  # what the core registry raised before the resolver
        OctaxVectorEnv("Pongg", 2)
    with pytest.raises(UnknownOptionError, match=r"unknown game 'Pongg' \(did you mean 'Pong'\?\); valid: 'Airplane'"):
        OctaxVectorEnv("Pongg", 2)
    with pytest.raises(gym.error.Error):
        gym.make("octax/Pongg-v0")


def test_single_env_refuses_vector_only_and_unknown_keywords(counter_rom):
    with pytest.raises(TypeError, match=r"unknown keyword\(s\) \['autoreset_mode'\]"):
        OctaxEnv(COUNTER, rom=counter_rom, autoreset_mode="same_step")


@pytest.mark.parametrize("actions, error, message", [
    (np.array([0, 1, 3]), InvalidActionError, r"action 3 is out of range; valid actions are 0..2"),
    (np.array([0, -1, 1]), InvalidActionError, r"action -1 is out of range"),
    (np.array([0, 1]), ValueError, r"actions must have shape \(3,\), one per env, got \(2,\)"),
    (np.zeros((3, 1), np.int64), ValueError, r"must have shape \(3,\)"),
    (np.array([0.0, 1.0, 2.0]), TypeError, "actions must be integers, got float64"),
    (np.array([True, False, True]), TypeError, "actions must be integers, got bool"),
    ([0, 1, 5], InvalidActionError, "action 5 is out of range"),
    (jnp.array([0, 1, 9]), ValueError, "action 9 is out of range"),
    (1, ValueError, r"must have shape \(3,\)"),
])
def test_bad_vector_actions(envs, actions, error, message):
    with pytest.raises(error, match=message):
        envs.step(actions)


def test_bad_torch_actions(envs):
    torch = pytest.importorskip("torch", reason="the torch extra is installed by `make test`")
    with pytest.raises(TypeError, match="actions must be integers, got a torch tensor of torch.float32"):
        envs.step(torch.zeros(3))
    with pytest.raises(ValueError, match="action 7 is out of range"):
        envs.step(torch.tensor([0, 7, 1]))
    with pytest.raises(ValueError, match=r"must have shape \(3,\)"):
        envs.step(torch.zeros(4, dtype=torch.int64))


@pytest.mark.parametrize("action, error, message", [
    (3, InvalidActionError, r"action 3 is out of range; valid actions are 0..2"),
    (1.0, TypeError, "an action is one integer in 0..2, got float64"),
    (np.array([1]), TypeError, r"got int64 of shape \(1,\)"),
    (True, TypeError, "got bool"),
])
def test_bad_single_actions(counter_rom, action, error, message):
    env = OctaxEnv(COUNTER, rom=counter_rom)
    env.reset(seed=0)
    with pytest.raises(error, match=message):
        env.step(action)


def test_step_before_reset(counter_rom):
    with pytest.raises(gym.error.ResetNeeded, match="reset"):
        OctaxVectorEnv(COUNTER, 2, rom=counter_rom).step(np.zeros(2, np.int64))


def test_valid_actions_still_work_after_refusals(envs):
    _, reward, *_ = envs.step(np.array([0, 1, 2], np.uint8))  # any integer dtype is fine
    assert list(reward) == [0, 4, 8]
