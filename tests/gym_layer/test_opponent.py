"""One seat of a two-player game against a fixed opponent (`opponent=`, `seat=`: `octax_gym.opponent`),
worked by hand on tests/two_player_games.py (TwoCounters: the scripted player holds its second key,
+2 a frame; TakeTurns: turn-based), then checked by Gymnasium's and SB3's env checkers and a short
SB3 PPO run on Space Racer.

Every view (seat, opponent kind) is its own compiled step, so the tests share a few of them.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import octax_core
import octax_gym
from octax_gym import IllegalMoveError, InvalidActionError, OctaxEnv, OctaxVectorEnv, OpponentRequiredError

from two_player_games import TAKE_TURNS, TAKE_TURNS_ROM, TWO_COUNTERS, TWO_COUNTERS_ROM


@pytest.fixture(scope="module")
def roms(tmp_path_factory):
    folder = tmp_path_factory.mktemp("opponent_roms")
    (folder / "two_counters.ch8").write_bytes(TWO_COUNTERS_ROM)
    (folder / "take_turns.ch8").write_bytes(TAKE_TURNS_ROM)
    return {"counters": folder / "two_counters.ch8", "turns": folder / "take_turns.ch8"}


def _counters(env) -> list[int]:
    return [int(env.state.machine.V[0, 0]), int(env.state.machine.V[0, 1])]


def test_scripted_opponent_runs_in_the_step(roms):
    env = OctaxEnv(TWO_COUNTERS, rom=roms["counters"], opponent="scripted")
    assert env.observation_space == gym.spaces.Box(0, 1, (5, 32, 64), np.uint8) and env.action_space.n == 3
    obs, info = env.reset(seed=0)
    assert obs.shape == (5, 32, 64) and (obs[-1] == 0).all()  # seat 0's player plane
    assert info["action_mask"].tolist() == [True] * 3 and info["current_player"] == -1
    obs, reward, terminated, truncated, info = env.step(1)
    assert reward == 4.0 and info["score"] == 4.0 and _counters(env) == [4, 8]  # the learner's reward alone
    assert not terminated and env.action_masks().tolist() == [True] * 3


def test_the_learner_in_seat_1(roms):
    """Three envs: test_action_check's seat-1 view against noop, whose compiled step this shares."""
    envs = OctaxVectorEnv(TWO_COUNTERS, 3, rom=roms["counters"], opponent="noop", seat=1)
    obs, _ = envs.reset(seed=0)
    assert (obs[:, -1] == 1).all()  # seat 1's player plane
    _, reward, *_ = envs.step(np.full(3, 2))  # seat 1's second key: +2 a frame
    assert reward.tolist() == [8.0] * 3
    np.testing.assert_array_equal(envs.state.machine.V[:, :2], [[0, 8]] * 3)


def test_a_function_opponent_sees_its_own_observation(roms):
    seen = []

    def opponent(obs):
        seen.append(np.array(obs))
        return 1

    env = OctaxEnv(TWO_COUNTERS, rom=roms["counters"], opponent=opponent)
    env.reset(seed=0)
    _, reward, *_ = env.step(0)
    assert reward == 0.0 and _counters(env) == [0, 4] and seen[0].shape == (5, 32, 64) and (seen[0][-1] == 1).all()
    envs = OctaxVectorEnv(TWO_COUNTERS, 2, rom=roms["counters"], opponent=lambda batch: np.array([1, 2]))
    obs, _ = envs.reset(seed=0)
    envs.step(np.array([0, 1]))
    np.testing.assert_array_equal(envs.state.machine.V[:, :2], [[0, 4], [4, 8]])
    bad = OctaxVectorEnv(TWO_COUNTERS, 2, rom=roms["counters"], opponent=lambda batch: np.array([1, 9]))
    bad.reset(seed=0)
    with pytest.raises(InvalidActionError, match="from the opponent: action 9 is out of range"):
        bad.step(np.array([0, 0]))


def test_same_seed_same_game_across_batch_sizes(roms):
    """The random opponent draws from each env's own key: row i of a batch seeded s is a single env seeded s + i."""
    options = dict(rom=roms["counters"], opponent="random")
    many, one = OctaxVectorEnv(TWO_COUNTERS, 3, autoreset_mode="disabled", **options), OctaxEnv(TWO_COUNTERS, **options)
    many.reset(seed=4), one.reset(seed=6)
    for action in (1, 0, 2, 2, 1):
        obs, reward, *_ = many.step(np.full(3, action))
        one_obs, one_reward, *_ = one.step(action)
        np.testing.assert_array_equal(obs[2], one_obs)
        assert reward[2] == one_reward
    assert len({tuple(row) for row in np.asarray(many.state.machine.V[:, :2])}) > 1  # the rows differ


def test_turn_based_masks_and_illegal_moves(roms):
    env = OctaxEnv(TAKE_TURNS, rom=roms["turns"], opponent="random")
    _, info = env.reset(seed=0)
    assert info["current_player"] == 0 and info["action_mask"].tolist() == [True, True]
    _, reward, _, _, info = env.step(1)
    assert reward == 1.0 and info["current_player"] == 1 and info["action_mask"].tolist() == [True, False]
    with pytest.raises(IllegalMoveError, match="seat first_0 \\(env 0\\) played action 1, but it is second_0's turn"):
        env.step(1)
    rewards = []
    for _ in range(40):  # the random opponent counts (its +1, the learner's -1) on some step
        _, reward, _, _, info = env.step(0)
        rewards.append(reward)
        if info["current_player"] == 0:
            break
    assert info["current_player"] == 0 and rewards[-1] == -1.0 and sum(rewards) == -1.0
    assert env.action_masks().tolist() == [True, True]


def test_gymnasium_make_and_the_checkers():
    from gymnasium.utils.env_checker import check_env as gym_check_env

    sb3 = pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make("octax/SpaceRacer-v0", opponent="random", seat=1)
    gym_check_env(env.unwrapped, skip_render_check=True)
    sb3_check_env(env.unwrapped, warn=False)
    model = sb3.PPO("MlpPolicy", env, n_steps=64, batch_size=64, n_epochs=1, seed=0,
                    policy_kwargs={"net_arch": [8]})
    model.learn(256)
    assert model.num_timesteps == 256


def test_every_two_player_game_is_registered():
    ids = [octax_gym.env_id(game) for game in octax_core.list_games(players=2)]
    assert list(octax_gym.TWO_PLAYER_ENV_IDS) == ids and "octax/SpaceRacer-v0" in ids
    for gym_id in ids:
        assert gym.spec(gym_id).entry_point == "octax_gym.envs.env:OctaxEnv"
    for game in octax_core.list_games(players=2):
        if not octax_core.get_spec(game).solo:  # refused before anything is built
            with pytest.raises(OpponentRequiredError, match="pass opponent="):
                gym.make(octax_gym.env_id(game))


def test_bad_opponents_are_named(roms):
    gym_id = octax_gym.register_game(TAKE_TURNS, roms["turns"])
    with pytest.raises(OpponentRequiredError, match="TakeTurns is played by two.*opponent="):
        gym.make(gym_id)
    with pytest.raises(ValueError, match="Pong is a one-player game; opponent= is for the two-player games"):
        OctaxEnv("Pong", opponent="random")
    with pytest.raises(ValueError, match="seat=1 picks the learner's side"):
        OctaxEnv("SpaceRacer", seat=1)
    with pytest.raises(octax_gym.UnknownOptionError, match="unknown opponent 'greedy'"):
        OctaxEnv("SpaceRacer", opponent="greedy")
    with pytest.raises(octax_gym.UnknownOptionError, match="unknown seat 2"):
        OctaxVectorEnv("SpaceRacer", 2, opponent="noop", seat=2)
    with pytest.raises(ValueError, match="no scripted policy"):
        OctaxEnv(TAKE_TURNS, rom=roms["turns"], opponent="scripted")
    assert issubclass(OpponentRequiredError, ValueError)
