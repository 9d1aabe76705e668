"""The Stable-Baselines3 adapter (octax_gym/integrations/sb3.py): the VecEnv contract as SB3 2.x defines it,
SB3's own wrappers on it, the paper's CNN and PPO settings, and PPO learning on it.

The contract tests run the Counter game (tests/counter_game.py) on 2 envs with max_episode_steps=4,
env 0 holding key 2 (+8 a step: reaches 24 and terminates at step 3), env 1 key 1 (+4 a step:
truncated at step 4), so every number below is worked by hand. They share one compiled program.
"""

from __future__ import annotations

import warnings

import cv2
import gymnasium
import numpy as np
import pytest
import torch
from gymnasium.vector import AutoresetMode
from stable_baselines3 import PPO
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.preprocessing import is_image_space, is_image_space_channels_first
from stable_baselines3.common.vec_env import (VecFrameStack, VecMonitor, VecTransposeImage, VecVideoRecorder,
                                              is_vecenv_wrapped)

from counter_game import COUNTER
from octax_gym import OctaxVectorEnv
from octax_gym.sb3 import PPO_KWARGS, OctaxCNNExtractor, OctaxSB3VecEnv, make_sb3_vec_env, ppo_kwargs
from torch_threads import one_torch_thread  # noqa: E402,F401  (autouse: one torch thread)

ACTIONS = np.array([2, 1], np.int64)  # SB3 hands over int64 actions


def counter(counter_rom, monitor=False, **kw):
    return make_sb3_vec_env(COUNTER, 2, rom=counter_rom, max_episode_steps=4, monitor=monitor, **kw)


def rows(reward, dones, infos):
    return [(float(reward[i]), bool(dones[i]), infos[i]["TimeLimit.truncated"], infos[i]["episode_step"],
             infos[i]["score"], "terminal_observation" in infos[i]) for i in range(2)]


# --- the VecEnv contract ------------------------------------------------------------------------


def test_spaces_dtypes_and_writable_arrays(counter_rom):
    venv = counter(counter_rom)
    space = venv.observation_space
    assert (space.shape, space.dtype, space.low.min(), space.high.max()) == ((4, 32, 64), np.uint8, 0, 255)
    assert is_image_space(space, check_channels=True) and is_image_space_channels_first(space)
    assert venv.action_space.n == 3 and venv.num_envs == 2
    obs = venv.reset()
    assert (obs.shape, obs.dtype) == ((2, 4, 32, 64), np.uint8) and obs.flags.writeable
    obs, reward, dones, infos = venv.step(ACTIONS)
    assert set(np.unique(obs).tolist()) == {0, 255}  # lit pixels 255, as SB3's image check wants
    assert (obs.shape, obs.dtype, reward.shape, reward.dtype, dones.shape, dones.dtype) == (
        (2, 4, 32, 64), np.uint8, (2,), np.float32, (2,), np.bool_)
    assert obs.flags.writeable and reward.flags.writeable  # SB3 adds bootstrap values into rewards
    assert isinstance(infos, list) and len(infos) == 2 and all(isinstance(i, dict) for i in infos)
    assert infos[0] == {"score": 8, "lives": 16, "episode_step": 1, "TimeLimit.truncated": False}


def test_same_step_reset_table(counter_rom):
    venv = counter(counter_rom)
    venv.reset()
    assert [i["episode_step"] for i in venv.reset_infos] == [0, 0]
    table, steps = [], []
    for _ in range(5):
        obs, reward, dones, infos = venv.step(ACTIONS)
        table.append(rows(reward, dones, infos))
        steps.append((obs, infos, [dict(i) for i in venv.reset_infos]))
    assert table == [  # (reward, done, TimeLimit.truncated, episode_step, score, terminal_observation?)
        [(8.0, False, False, 1, 8, False), (4.0, False, False, 1, 4, False)],
        [(8.0, False, False, 2, 16, False), (4.0, False, False, 2, 8, False)],
        [(8.0, True, False, 3, 24, True), (4.0, False, False, 3, 12, False)],  # env 0 terminates
        [(8.0, False, False, 1, 8, False), (4.0, True, True, 4, 16, True)],    # env 1 is cut off
        [(8.0, False, False, 2, 16, False), (4.0, False, False, 1, 4, False)],
    ]
    obs, infos, reset_infos = steps[2]
    assert reset_infos[0]["episode_step"] == 0 and reset_infos[0]["score"] == 0  # the new episode's info
    terminal = infos[0]["terminal_observation"]
    assert (terminal.shape, terminal.dtype) == ((4, 32, 64), np.uint8) and terminal.flags.writeable
    # The terminal observation shows the digit drawn at y = 24 (the last score); the returned
    # observation is the new episode's start-up screen.
    assert (terminal[-1, 24:29] == 255).any() and not terminal[-1, :24].any()
    assert not obs[0, -1, 24:29].any()
    assert steps[3][1][1]["terminal_observation"].shape == (4, 32, 64)


def test_seed_applies_at_the_next_reset_only_and_seeds_env_i_with_s_plus_i(counter_rom):
    def trajectory(venv, actions=ACTIONS, steps=6):
        out = [venv.reset()]
        out += [venv.step(actions)[0] for _ in range(steps)]
        return np.stack(out)

    venv = counter(counter_rom)
    assert venv.seed(5) == [5, 6]
    first = trajectory(venv)
    assert venv._seeds == [None, None]  # used once
    assert not np.array_equal(trajectory(venv), first)  # an unseeded reset continues the key chain
    venv.seed(5)
    assert np.array_equal(trajectory(venv), first)
    venv.seed(6)
    swapped = trajectory(venv, ACTIONS[::-1].copy())
    assert np.array_equal(swapped[:, 0], first[:, 1])  # env 0 seeded 6 plays as env 1 seeded 5
    assert not np.array_equal(swapped[:, 1], first[:, 0])
    # the same as the Gymnasium vector env it wraps, reset with seed 5
    envs = OctaxVectorEnv(COUNTER, 2, rom=counter_rom, max_episode_steps=4, obs_scale=255,
                          autoreset_mode=AutoresetMode.SAME_STEP)
    gym_obs = [np.array(envs.reset(seed=5)[0])] + [np.array(envs.step(ACTIONS)[0]) for _ in range(6)]
    assert np.array_equal(np.stack(gym_obs), first)


def test_set_options_reset_mask_resets_only_those_rows(counter_rom):
    venv = counter(counter_rom)
    venv.reset()
    for _ in range(2):
        before = venv.step(ACTIONS)[0]
    venv.set_options({"reset_mask": np.array([True, False])})
    obs = venv.reset()
    assert [i["episode_step"] for i in venv.reset_infos] == [0, 2]
    assert np.array_equal(obs[1], before[1]) and not np.array_equal(obs[0], before[0])
    assert venv._options == [{}, {}]  # used once
    infos = venv.step(ACTIONS)[3]
    assert [i["episode_step"] for i in infos] == [1, 3]


@pytest.mark.parametrize("options, error, match", [
    ({"bogus": 1}, ValueError, "unknown reset option"),
    ([{"reset_mask": np.array([True, False])}, {"reset_mask": np.array([False, True])}], ValueError,
     "same options"),
    ({"reset_mask": np.array([1, 0])}, ValueError, "bool array"),
])
def test_bad_options_are_refused_at_reset(counter_rom, options, error, match):
    venv = counter(counter_rom)
    venv.reset()
    venv.set_options(options)
    with pytest.raises(error, match=match):
        venv.reset()


def test_attributes_methods_and_wrapped(counter_rom):
    venv = counter(counter_rom, render_mode="rgb_array", render_scale=1)
    assert venv.get_attr("render_mode") == ["rgb_array"] * 2 and venv.render_mode == "rgb_array"
    assert venv.get_attr("game", indices=1) == ["Counter"] and venv.has_attr("game")
    assert not venv.has_attr("no_such_thing")
    with pytest.raises(AttributeError):
        venv.get_attr("no_such_thing")
    with pytest.raises(IndexError, match="0..1"):
        venv.get_attr("game", indices=[2])
    venv.set_attr("render_scale", 2)
    assert venv.get_attr("render_scale") == [2, 2]
    with pytest.raises(ValueError, match="indices=None"):
        venv.set_attr("render_scale", 1, indices=[0])
    venv.reset()
    frames = venv.env_method("render", indices=[0])
    assert len(frames) == 1 and len(frames[0]) == 2 and frames[0][0].shape == (64, 128, 3)
    assert venv.env_is_wrapped(Monitor) == [False, False]
    with pytest.raises(TypeError, match="autoreset_mode"):
        OctaxSB3VecEnv(COUNTER, 2, rom=counter_rom, autoreset_mode="next_step")
    with pytest.raises(TypeError, match="backend"):
        OctaxSB3VecEnv(COUNTER, 2, rom=counter_rom, backend="torch")
    with pytest.raises(RuntimeError, match="step_async"):
        venv.step_wait()
    venv.close()


def test_get_images_render_and_video_recorder(counter_rom, tmp_path):
    venv = counter(counter_rom, render_mode="rgb_array", render_scale=1)
    assert venv.metadata["render_fps"] == 15 and "rgb_array" in venv.metadata["render_modes"]
    venv.reset()
    images = venv.get_images()
    assert len(images) == 2 and all(i.shape == (32, 64, 3) and i.dtype == np.uint8 for i in images)
    assert venv.render().shape == (64, 64, 3)  # SB3 tiles the two frames (2 rows x 1 column)
    recorder = VecVideoRecorder(venv, str(tmp_path), record_video_trigger=lambda step: step == 0, video_length=5,
                                name_prefix="counter")
    recorder.reset()
    for _ in range(6):
        recorder.step(ACTIONS)
    recorder.close()
    (video,) = tmp_path.glob("counter-step-0-to-step-5.mp4")
    capture = cv2.VideoCapture(str(video))
    decoded = []
    while (frame := capture.read())[0]:
        decoded.append(frame[1])
    # 6 frames recorded (reset + 5 steps); moviepy's writer may drop the last one.
    assert len(decoded) in (5, 6) and decoded[0].shape == (64, 64, 3)
    assert max(frame.max() for frame in decoded) > 200  # the digit is drawn
    assert capture.get(cv2.CAP_PROP_FPS) == pytest.approx(15)

    plain = counter(counter_rom)
    plain.reset()
    with pytest.warns(UserWarning, match="rgb_array"):
        assert plain.get_images() == [None, None]


# --- SB3's wrappers -----------------------------------------------------------------------------


def test_vec_monitor_reports_episodes(counter_rom):
    venv = counter(counter_rom, monitor=True)
    assert isinstance(venv, VecMonitor) and isinstance(venv.unwrapped, OctaxSB3VecEnv)
    venv.seed(0)
    venv.reset()
    episodes = []
    for _ in range(4):
        _, _, dones, infos = venv.step(ACTIONS)
        episodes += [(i, infos[i]["episode"]["r"], infos[i]["episode"]["l"]) for i in np.flatnonzero(dones)]
    assert episodes == [(0, 24.0, 3), (1, 16.0, 4)]
    mean, std = evaluate_policy(FixedAction(), venv, n_eval_episodes=4)  # no Monitor warning
    assert (mean, std) == (24.0, 0.0)


class FixedAction:
    """A `predict` that always holds key 2: every Counter episode scores 24 in 3 steps."""

    def predict(self, obs, state=None, episode_start=None, deterministic=False):
        return np.full(len(obs), 2), None


def test_frame_stack_and_no_transpose(counter_rom):
    venv = VecFrameStack(counter(counter_rom), n_stack=2)
    obs = venv.reset()
    assert obs.shape == (2, 8, 32, 64) and obs.dtype == np.uint8
    for _ in range(3):
        obs, _, dones, infos = venv.step(ACTIONS)
    assert dones.tolist() == [True, False] and infos[0]["terminal_observation"].shape == (8, 32, 64)
    model = PPO("CnnPolicy", counter(counter_rom), **ppo_kwargs(2))
    assert not is_vecenv_wrapped(model.get_env(), VecTransposeImage)  # already channel-first


# --- the paper's CNN and PPO settings -----------------------------------------------------------


def test_cnn_extractor_layers_follow_the_paper(counter_rom):
    space = counter(counter_rom).observation_space
    extractor = OctaxCNNExtractor(space, head_dim=None)
    x = torch.zeros(3, 4, 32, 64).transpose(-1, -2)  # the torso's width-first layout
    shapes = []
    for layer in extractor.torso.convs:
        x = layer(x)
        if isinstance(layer, torch.nn.Conv2d):
            shapes.append(tuple(x.shape[1:]))
    assert shapes == [(32, 15, 15), (64, 6, 6), (64, 4, 4)]
    assert extractor.features_dim == 1024 and extractor(torch.zeros(3, 4, 32, 64)).shape == (3, 1024)
    headed = OctaxCNNExtractor(space)
    assert headed.features_dim == 256 and headed(torch.rand(3, 4, 32, 64)).shape == (3, 256)
    assert torch.all(headed(torch.rand(3, 4, 32, 64)) >= 0)  # ReLU after the head
    with pytest.raises(ValueError, match=r"\(frames, 32, 64\)"):
        OctaxCNNExtractor(gymnasium.spaces.Box(0, 255, (4, 64, 32), np.uint8))


def test_ppo_kwargs_build_the_papers_actor_critic(counter_rom):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # 16 envs x 32 steps = one 512-sample minibatch: nothing to warn
        model = PPO("CnnPolicy", make_sb3_vec_env(COUNTER, 16, rom=counter_rom), **PPO_KWARGS)
    assert (model.n_steps, model.batch_size, model.n_epochs, model.gamma, model.gae_lambda, model.ent_coef,
            model.vf_coef, model.max_grad_norm) == (32, 512, 4, 0.99, 0.95, 0.01, 0.25, 0.5)
    assert model.learning_rate == 5e-4 and model.clip_range(1.0) == 0.2
    policy = model.policy
    assert isinstance(policy.features_extractor, OctaxCNNExtractor) and policy.features_dim == 1024
    assert policy.pi_features_extractor is policy.vf_features_extractor  # one shared torso
    assert [m.out_features for m in policy.mlp_extractor.policy_net if isinstance(m, torch.nn.Linear)] == [256]
    assert [m.out_features for m in policy.mlp_extractor.value_net if isinstance(m, torch.nn.Linear)] == [256]
    assert isinstance(policy.mlp_extractor.policy_net[1], torch.nn.ReLU)
    assert policy.optimizer.defaults["eps"] == 1e-8 and policy.optimizer.defaults["lr"] == 5e-4
    # The paper's agent: convs 4*32*8*4+32, 32*64*16+64, 64*64*9+64; two 1024->256 layers;
    # 256->3 logits and 256->1 value.
    expected = 4128 + 32832 + 36928 + 2 * (1024 * 256 + 256) + (256 * 3 + 3) + (256 + 1)
    assert sum(p.numel() for p in policy.parameters()) == expected == 599_716


def test_ppo_kwargs_scale_the_batch_and_are_fresh_dicts():
    assert ppo_kwargs(64)["batch_size"] == 64 and ppo_kwargs(512)["batch_size"] == 512
    assert ppo_kwargs(64, num_minibatches=8)["batch_size"] == 256 and ppo_kwargs(1)["batch_size"] == 2
    one, two = ppo_kwargs(), ppo_kwargs()
    one["policy_kwargs"]["net_arch"]["pi"].append(64)
    assert two["policy_kwargs"]["net_arch"]["pi"] == [256] and PPO_KWARGS["policy_kwargs"]["net_arch"]["pi"] == [256]


def test_ppo_learns_1k_steps_on_brix(tmp_path):
    venv = make_sb3_vec_env("Brix", 8)
    model = PPO("CnnPolicy", venv, **ppo_kwargs(8), seed=0)
    before = [p.detach().clone() for p in model.policy.parameters()]
    model.learn(1024)
    assert model.num_timesteps == 1024
    after = list(model.policy.parameters())
    assert all(torch.isfinite(p).all() for p in after)
    assert all(not torch.equal(a, b) for a, b in zip(before, after))  # every layer was trained
    logged = model.logger.name_to_value
    assert np.isfinite(logged["train/value_loss"]) and np.isfinite(logged["train/entropy_loss"])
    obs = venv.reset()
    actions, _ = model.predict(obs)
    assert actions.shape == (8,) and set(actions.tolist()) <= {0, 1, 2}
    model.save(tmp_path / "brix")
    loaded = PPO.load(tmp_path / "brix", env=venv)
    assert np.array_equal(loaded.predict(obs, deterministic=True)[0], model.predict(obs, deterministic=True)[0])
