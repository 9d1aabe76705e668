"""`octax_gym.MultiAgentVectorEnv`: both seats of a two-player game, batched, on the two games worked
by hand in tests/two_player_games.py (TwoCounters simultaneous, TakeTurns turn-based zero-sum).

Envs of one (game, config, ROM) share one compiled step, and each batch size and autoreset mode
compiles once: the fixtures below are module-wide, and every test reuses their batch sizes.
"""

from __future__ import annotations

import gymnasium as gym
import jax.numpy as jnp
import numpy as np
import pytest

import octax_gym
from octax_gym import IllegalMoveError, InvalidActionError, MultiAgentVectorEnv

from two_player_games import TAKE_TURNS, TAKE_TURNS_ROM, TWO_COUNTERS, TWO_COUNTERS_ROM


@pytest.fixture(scope="module")
def roms(tmp_path_factory):
    folder = tmp_path_factory.mktemp("two_player_roms")
    (folder / "two_counters.ch8").write_bytes(TWO_COUNTERS_ROM)
    (folder / "take_turns.ch8").write_bytes(TAKE_TURNS_ROM)
    return folder


@pytest.fixture(scope="module")
def counters(roms):
    return MultiAgentVectorEnv(TWO_COUNTERS, 3, rom=roms / "two_counters.ch8")


@pytest.fixture(scope="module")
def turns(roms):
    return MultiAgentVectorEnv(TAKE_TURNS, 2, rom=roms / "take_turns.ch8")


def test_spaces_shapes_and_dtypes(counters):
    assert counters.agents == ("first_0", "second_0") and counters.num_actions == 3
    assert counters.single_observation_space == gym.spaces.Box(0, 1, (2, 5, 32, 64), np.uint8)
    assert counters.observation_space.shape == (3, 2, 5, 32, 64)
    assert counters.agent_observation_space == gym.spaces.Box(0, 1, (5, 32, 64), np.uint8)
    assert counters.single_action_space == gym.spaces.MultiDiscrete([3, 3])
    assert counters.action_space.shape == (3, 2) and counters.agent_action_space == gym.spaces.Discrete(3)
    obs, info = counters.reset(seed=0)
    assert obs.shape == (3, 2, 5, 32, 64) and obs.dtype == np.uint8 and obs in counters.observation_space
    assert (obs[:, 0, 4] == 0).all() and (obs[:, 1, 4] == 1).all()  # the player plane
    np.testing.assert_array_equal(obs[:, 0, :4], obs[:, 1, :4])  # one screen, two readers
    obs, reward, terminated, truncated, info = counters.step(counters.action_space.sample())
    assert obs.shape == (3, 2, 5, 32, 64) and reward.shape == (3, 2) and reward.dtype == np.float32
    assert terminated.shape == truncated.shape == (3,) and terminated.dtype == np.bool_
    assert info["score"].shape == (3, 2) and info["current_player"].tolist() == [-1, -1, -1]
    assert info["legal_action_mask"].shape == (3, 2, 3) and info["legal_action_mask"].all()
    assert all(info[f"_{key}"].all() for key in ("score", "current_player", "legal_action_mask"))
    assert counters.action_masks().shape == (3, 2, 3)


def test_each_seats_keys_and_rewards(counters):
    counters.reset(seed=0)
    _, reward, *_, info = counters.step(np.array([[1, 0], [0, 2], [1, 2]]))
    np.testing.assert_array_equal(reward, [[4, 0], [0, 8], [4, 8]])  # 4 frames a step
    np.testing.assert_array_equal(info["score"], [[4, 0], [0, 8], [4, 8]])
    _, reward, *_ = counters.step([[0, 1], [2, 0], [0, 0]])  # a list is taken too
    np.testing.assert_array_equal(reward, [[0, 4], [8, 0], [0, 0]])


def test_the_shared_episode_ends_and_autoresets(counters):
    counters.reset(seed=0)
    flags = [bool(counters.step(np.array([[0, 2]] * 3))[2][0]) for _ in range(4)]
    assert flags == [False, False, True, False]  # V1: 8, 16, 24 -> over; NEXT_STEP: then the reset
    assert counters.state.machine.V[0, 1] == 0


def test_turns_masks_and_zero_sum(turns):
    obs, info = turns.reset(seed=0)
    assert info["current_player"].tolist() == [0, 0]
    np.testing.assert_array_equal(info["legal_action_mask"][0], [[True, True], [True, False]])
    _, reward, _, _, info = turns.step(np.array([[1, 0], [0, 0]]))  # env 0: seat 0 counts; env 1 waits
    np.testing.assert_array_equal(reward, [[1, -1], [0, 0]])
    assert info["current_player"].tolist() == [1, 0]
    np.testing.assert_array_equal(info["legal_action_mask"][0], [[True, False], [True, True]])
    rewards = [reward]
    for actions in ([[0, 1], [1, 0]], [[1, 0], [0, 1]], [[0, 0], [0, 0]]):
        _, reward, _, _, info = turns.step(np.array(actions))
        rewards.append(reward)
    np.testing.assert_array_equal(np.sum(rewards, axis=0).sum(axis=1), [0, 0])  # zero-sum, every env
    assert (np.asarray(rewards).sum(axis=2) == 0).all()  # and every step
    assert info["current_player"].tolist() == [1, 0]


def test_errors_are_named(turns):
    turns.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(2, 2\), one per env and seat \(first_0, second_0\)"):
        turns.step(np.array([1, 0]))
    with pytest.raises(TypeError, match="integers"):
        turns.step(np.zeros((2, 2), np.float32))
    with pytest.raises(InvalidActionError, match=r"action 5 is out of range.*\(env 1, seat second_0\)"):
        turns.step(np.array([[0, 0], [0, 5]]))
    with pytest.raises(IllegalMoveError, match="seat second_0 \\(env 0\\) played action 1, but it is first_0's turn"):
        turns.step(np.array([[0, 1], [0, 0]]))
    assert int(turns.state.episode_step[0]) == 0  # nothing ran
    turns.step(np.array([[1, 0], [0, 0]]))
    with pytest.raises(IllegalMoveError, match="first_0 \\(env 0\\).*second_0's turn.*device array"):
        turns.step(jnp.array([[1, 0], [0, 0]]))  # checked in the step; numpy backend: raised by it
    assert issubclass(IllegalMoveError, ValueError) and octax_gym.IllegalMoveError is IllegalMoveError


def test_one_player_games_and_unknown_names_are_refused():
    with pytest.raises(ValueError, match="one-player game; two-player games: .*SpaceRacer"):
        octax_gym.make_multi_vec("Pong", 2)
    with pytest.raises(octax_gym.UnknownOptionError, match="unknown two-player game 'Spacerace'.*SpaceRacer"):
        MultiAgentVectorEnv("Spacerace", 2)
    with pytest.raises(TypeError, match="opponent"):
        MultiAgentVectorEnv("SpaceRacer", 2, opponent="random")


def test_torch_backend_shares_memory(roms):
    torch = pytest.importorskip("torch")
    envs = octax_gym.make_multi_vec(TWO_COUNTERS, 3, rom=roms / "two_counters.ch8", backend="torch")
    obs, _ = envs.reset(seed=0)
    assert isinstance(obs, torch.Tensor) and obs.data_ptr() == envs._obs.unsafe_buffer_pointer()
    obs, reward, terminated, _, info = envs.step(torch.tensor([[1, 0], [0, 2], [1, 2]]))
    assert obs.data_ptr() == envs._obs.unsafe_buffer_pointer() and obs.shape == (3, 2, 5, 32, 64)
    assert reward.tolist() == [[4, 0], [0, 8], [4, 8]] and info["legal_action_mask"].dtype == torch.bool
    with pytest.raises(InvalidActionError, match="seat second_0"):
        envs.step(torch.tensor([[0, 0], [0, 0], [0, 7]]))
        envs.close()  # at the latest


def test_same_seed_same_game_across_batch_sizes(roms):
    """Row i of a batch seeded s plays the game a batch of one seeded s + i plays (sticky actions draw
    from each env's own key). The batch of one is PettingZoo's env (autoreset disabled, the same
    play while no episode ends, as none does in 5 steps), whose compiled step it shares."""
    options = dict(rom=roms / "two_counters.ch8", repeat_action_probability=0.5)
    many = MultiAgentVectorEnv(TWO_COUNTERS, 3, **options)
    one = MultiAgentVectorEnv(TWO_COUNTERS, 1, autoreset_mode="disabled", **options)
    many.reset(seed=7), one.reset(seed=9)
    rng = np.random.default_rng(0)
    for _ in range(5):
        actions = rng.integers(0, 3, (3, 2))
        obs, reward, *_ = many.step(actions)
        one_obs, one_reward, *_ = one.step(actions[2:])
        np.testing.assert_array_equal(obs[2], one_obs[0])
        np.testing.assert_array_equal(reward[2], one_reward[0])
