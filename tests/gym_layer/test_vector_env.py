"""OctaxVectorEnv against N single envs, batch-size independence, seeding, partial resets, spaces,
registration and Gymnasium's own vector wrappers.

Every Counter env here is one of a few compiled steps that the gym tests share (a step compiles
once per game, options, autoreset mode and batch size): three envs (two where a second batch size
is the point), RANDOM_KW or the defaults."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import octax_core
import octax_gym
from counter_game import COUNTER
from octax_gym import OctaxEnv, OctaxVectorEnv

# Randomness everywhere it can enter: sticky actions, no-op starts, the game's own CXNN draws.
RANDOM_KW = dict(max_episode_steps=5, repeat_action_probability=0.3, noop_max=3)


def random_actions(steps, num_envs, seed=0):
    return np.random.default_rng(seed).integers(0, 3, size=(steps, num_envs))


def run_vector(envs, seed, actions):
    obs, _ = envs.reset(seed=seed)
    out = [(np.array(obs),)]
    for batch in actions:
        obs, reward, terminated, truncated, info = envs.step(batch)
        out.append((np.array(obs), reward.copy(), terminated.copy(), truncated.copy(), info["score"].copy()))
    return out


def test_vector_env_equals_single_envs_under_the_same_seeds(counter_rom):
    """Row i of a vector env reset with seed s plays as a single env reset with seed s + i, the
    single env calling reset() where the vector env autoresets (NEXT_STEP)."""
    num_envs, steps, seed = 3, 14, 11
    actions = random_actions(steps, num_envs)
    vector = run_vector(OctaxVectorEnv(COUNTER, num_envs, rom=counter_rom, **RANDOM_KW), seed, actions)
    episodes_ended = 0
    for i in range(num_envs):
        env = OctaxEnv(COUNTER, rom=counter_rom, **RANDOM_KW)
        obs, _ = env.reset(seed=seed + i)
        assert (obs == vector[0][0][i]).all()
        needs_reset = False
        for t in range(steps):
            if needs_reset:  # NEXT_STEP: this step is the reset
                obs, info = env.reset()
                reward, terminated, truncated, score = 0.0, False, False, info["score"]
                needs_reset = False
            else:
                obs, reward, terminated, truncated, info = env.step(int(actions[t, i]))
                score, needs_reset = info["score"], terminated or truncated
                episodes_ended += needs_reset
            v_obs, v_reward, v_terminated, v_truncated, v_score = vector[t + 1]
            assert (obs == v_obs[i]).all(), (i, t)
            assert (reward, terminated, truncated, score) == (v_reward[i], v_terminated[i], v_truncated[i], v_score[i])
    assert episodes_ended >= 3  # the comparison went through resets


def test_trajectories_do_not_depend_on_the_batch_size(counter_rom):
    actions = random_actions(12, 3, seed=1)
    big = run_vector(OctaxVectorEnv(COUNTER, 3, rom=counter_rom, **RANDOM_KW), 7, actions)
    small = run_vector(OctaxVectorEnv(COUNTER, 2, rom=counter_rom, **RANDOM_KW), 7, actions[:, :2])
    for big_step, small_step in zip(big, small):
        for big_field, small_field in zip(big_step, small_step):
            np.testing.assert_array_equal(big_field[:2], small_field)


def test_same_seed_same_trajectory_other_seed_differs(counter_rom):
    actions = random_actions(8, 2)
    runs = [run_vector(OctaxVectorEnv(COUNTER, 2, rom=counter_rom, **RANDOM_KW), seed, actions) for seed in (3, 3, 4)]
    stack = [np.stack([step[0] for step in run]) for run in runs]
    assert (stack[0] == stack[1]).all()
    assert not (stack[0] == stack[2]).all()  # the digit's x position is drawn by CXNN


def test_seed_list_and_unseeded_resets(counter_rom):
    envs = OctaxVectorEnv(COUNTER, 2, rom=counter_rom, **RANDOM_KW)
    actions = random_actions(4, 2)
    # seeded with the int 9, row 0 starts where the list's row 1 (seed 9) does
    by_list = run_vector(envs, [5, 9], actions)
    by_int = run_vector(OctaxVectorEnv(COUNTER, 3, rom=counter_rom, **RANDOM_KW), 9, np.repeat(actions[:, 1:], 3, axis=1))
    for a, b in zip(by_list, by_int):
        np.testing.assert_array_equal(a[0][1], b[0][0])
    envs.reset()  # no seed: the key chains go on, nothing raises
    with pytest.raises(ValueError, match="seed must be"):
        envs.reset(seed=[1, 2, 3])
    with pytest.raises(ValueError, match="seed must be"):
        envs.reset(seed=-1)


def test_reset_mask_resets_only_the_marked_rows(counter_rom):
    envs = OctaxVectorEnv(COUNTER, 3, rom=counter_rom, autoreset_mode="disabled")
    envs.reset(seed=0)
    for _ in range(2):
        obs, *_ , info = envs.step(np.array([1, 1, 2]))
    before = np.array(obs)
    obs, info = envs.reset(options={"reset_mask": np.array([False, True, False])})
    assert list(info["score"]) == [8, 0, 16] and list(info["episode_step"]) == [2, 0, 2]
    assert (obs[0] == before[0]).all() and (obs[2] == before[2]).all()
    _, reward, *_ = envs.step(np.array([1, 1, 1]))
    assert list(reward) == [4, 4, 4]
    for bad in (np.array([1, 0, 1]), np.array([True, False]), [True, False, True], np.zeros(3, bool)):
        with pytest.raises(ValueError, match="reset_mask"):
            envs.reset(options={"reset_mask": bad})
    with pytest.raises(ValueError, match="unknown reset option"):
        envs.reset(options={"mask": np.ones(3, bool)})


def test_spaces_and_dtypes(counter_rom):
    # two envs in SAME_STEP with obs_scale=255: test_sb3's compiled step (the mode changes no space)
    envs = OctaxVectorEnv(COUNTER, 2, rom=counter_rom, obs_scale=255, autoreset_mode="same_step")
    assert envs.single_observation_space == gym.spaces.Box(0, 255, (4, 32, 64), np.uint8)
    assert envs.observation_space.shape == (2, 4, 32, 64)
    assert envs.single_action_space == gym.spaces.Discrete(3)
    assert envs.action_space == gym.spaces.MultiDiscrete([3, 3])
    obs, info = envs.reset(seed=0)
    assert obs.dtype == np.uint8 and set(np.unique(obs)) <= {0, 255} and obs in envs.observation_space
    obs, reward, terminated, truncated, info = envs.step(envs.action_space.sample())
    assert (reward.dtype, terminated.dtype, truncated.dtype) == (np.float32, np.bool_, np.bool_)
    assert info["score"].dtype == np.float32 and info["lives"].dtype == np.int32
    assert all(info[f"_{key}"].all() for key in ("score", "lives", "episode_step"))


def test_every_game_is_registered_with_both_entry_points():
    ids = [octax_gym.env_id(game) for game in octax_core.list_games()]
    assert list(octax_gym.ENV_IDS) == ids and len(ids) == len(octax_core.list_games()) >= 39
    for gym_id in ids:
        spec = gym.spec(gym_id)
        assert spec.entry_point == "octax_gym.envs.env:OctaxEnv"
        assert spec.vector_entry_point == "octax_gym.envs.vector:OctaxVectorEnv"
    assert "octax/Pong-v0" in gym.registry and gym.register_envs(octax_gym) is None


def test_make_and_make_vec_pick_our_envs():
    envs = gym.make_vec("octax/Pong-v0", num_envs=2, max_episode_steps=7)
    assert isinstance(envs, OctaxVectorEnv) and envs.num_envs == 2
    assert envs.spec.id == "octax/Pong-v0" and envs.params.max_episode_steps == 7
    env = gym.make("octax/Pong-v0")
    assert isinstance(env.unwrapped, OctaxEnv) and env.unwrapped.game_spec.id == "Pong"
    obs, _ = env.reset(seed=0)
    assert obs.shape == (4, 32, 64) and obs.any()  # Pong's court is drawn


def test_record_episode_statistics(counter_rom):
    envs = gym.wrappers.vector.RecordEpisodeStatistics(
        OctaxVectorEnv(COUNTER, 3, rom=counter_rom, max_episode_steps=4))
    envs.reset(seed=0)
    episodes = []
    for _ in range(8):
        *_, info = envs.step(np.array([2, 1, 1]))
        if "episode" in info:
            episodes += [(i, float(info["episode"]["r"][i]), int(info["episode"]["l"][i]))
                         for i in np.flatnonzero(info["_episode"])]
    # env 0: +8 x 3 steps = 24 (terminated); envs 1 and 2: +4 x 4 steps = 16 (truncated); NEXT_STEP
    # resets in between do not count.
    assert episodes == [(0, 24.0, 3), (1, 16.0, 4), (2, 16.0, 4), (0, 24.0, 3)]


def test_jax_to_torch_wrapper(counter_rom):
    torch = pytest.importorskip("torch", reason="the torch extra is part of `make test`")
    envs = gym.wrappers.vector.JaxToTorch(OctaxVectorEnv(COUNTER, 3, rom=counter_rom, backend="jax"))
    obs, info = envs.reset(seed=0)
    assert isinstance(obs, torch.Tensor) and obs.dtype == torch.uint8 and obs.shape == (3, 4, 32, 64)
    obs, reward, terminated, truncated, info = envs.step(torch.tensor([1, 2, 0]))
    assert reward.tolist() == [4.0, 8.0, 0.0] and terminated.dtype == torch.bool


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_vector_env_equals_gymnasium_sync_vector_env_over_single_envs(counter_rom, mode):
    """Gymnasium's own SyncVectorEnv over OctaxEnv copies (seeded s, s+1, ...) is the reference.

    In SAME_STEP the new episode's randomness differs (see docs/gymnasium.md), so there only
    everything up to each env's first end must match, plus the final observations."""
    num_envs, steps, seed = 3, 12, 2
    kw = dict(max_episode_steps=4, repeat_action_probability=0.3)  # no no-op starts: resets equal
    actions = random_actions(steps, num_envs, seed=5)
    ours = OctaxVectorEnv(COUNTER, num_envs, rom=counter_rom, autoreset_mode=mode, **kw)
    sync = gym.vector.SyncVectorEnv([lambda: OctaxEnv(COUNTER, rom=counter_rom, **kw)] * num_envs,
                                    autoreset_mode=mode)
    ended = np.zeros(num_envs, bool)
    (obs_a, info_a), (obs_b, info_b) = ours.reset(seed=seed), sync.reset(seed=seed)
    np.testing.assert_array_equal(obs_a, obs_b)
    np.testing.assert_array_equal(info_a["score"], info_b["score"])
    for t in range(steps):
        obs_a, reward_a, term_a, trunc_a, info_a = ours.step(actions[t])
        obs_b, reward_b, term_b, trunc_b, info_b = sync.step(actions[t])
        live = ~ended if mode == AutoresetMode.SAME_STEP else np.ones(num_envs, bool)
        np.testing.assert_array_equal(np.asarray(obs_a)[live], obs_b[live])
        np.testing.assert_array_equal(reward_a[live], reward_b[live])
        np.testing.assert_array_equal(term_a[live], term_b[live])
        np.testing.assert_array_equal(trunc_a[live], trunc_b[live])
        if mode == AutoresetMode.SAME_STEP and "final_obs" in info_b:
            for i in np.flatnonzero(info_b["_final_obs"] & live):
                assert info_a["_final_obs"][i]
                np.testing.assert_array_equal(info_a["final_obs"][i], info_b["final_obs"][i])
                assert info_a["final_info"]["score"][i] == info_b["final_info"]["score"][i]
        ended |= np.asarray(term_b | trunc_b)
    assert ended.all()
