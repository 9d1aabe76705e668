"""TorchRL: the native batched env (`octax_gym.torchrl`), GymWrapper over OctaxVectorEnv, the paper's network.

Most tests play the Counter game (tests/counter_game.py) with three envs and fixed actions [2, 1, 0]
(+8, +4, +0 a step) and max_episode_steps=4: env 0 reaches 24 and terminates at step 3, envs 1 and
2 are truncated at step 4. The digit is drawn at y = score, so the screen tells which episode it is.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from counter_game import COUNTER
from octax_gym import OctaxVectorEnv

torch = pytest.importorskip("torch", reason="the torchrl extra is installed by `make test`")
pytest.importorskip("torchrl", reason="the torchrl extra is installed by `make test`")

from torchrl.collectors import Collector
from torchrl.data import Categorical
from torchrl.envs import GymWrapper
from torchrl.envs.utils import check_env_specs

from octax_gym.networks import FEATURES, ActorCritic, OctaxCNN
from octax_gym.torchrl import OctaxTorchRLEnv, make_torchrl_env

N = 3
ACTIONS = torch.tensor([2, 1, 0])
EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "train_torchrl_ppo.py"


def make(counter_rom, **kw) -> OctaxTorchRLEnv:
    return make_torchrl_env(COUNTER, N, rom=counter_rom, max_episode_steps=4, **kw)


def fixed_policy(td):
    return td.set("action", ACTIONS.clone())


def step(env, td):
    """One env.step with the fixed actions; returns the "next" tensordict."""
    return env.step(fixed_policy(td))["next"]


def test_specs_dtypes_and_shapes(counter_rom):
    env = make(counter_rom)
    assert env.batch_size == (N,) and isinstance(env.action_spec, Categorical) and env.action_spec.n == 3
    assert env.action_spec.dtype == torch.int64
    td = env.reset()
    assert td["observation"].dtype == torch.uint8 and td["observation"].shape == (N, 4, 32, 64)
    assert all(td[k].dtype == torch.bool and td[k].shape == (N, 1) for k in ("done", "terminated", "truncated"))
    nxt = step(env, td)
    dtypes = {k: nxt[k].dtype for k in ("observation", "reward", "done", "score", "lives", "episode_step")}
    assert dtypes == {"observation": torch.uint8, "reward": torch.float32, "done": torch.bool,
                      "score": torch.float32, "lives": torch.int32, "episode_step": torch.int32}
    assert nxt["reward"].shape == (N, 1) and nxt["score"].shape == (N,)
    assert nxt["reward"].squeeze(-1).tolist() == [8.0, 4.0, 0.0] and nxt["lives"].tolist() == [16, 20, 24]
    assert env.full_observation_spec.is_in(nxt.select(*env.full_observation_spec.keys()))


def test_tensors_are_the_jax_buffers(counter_rom):
    """DLPack both ways: the observation tensor is the JAX output buffer itself, no copy."""
    env = make(counter_rom)
    td = env.reset()
    assert td["observation"].data_ptr() == env.vector_env._obs.unsafe_buffer_pointer()
    nxt = step(env, td)
    assert nxt["observation"].data_ptr() == env.vector_env._obs.unsafe_buffer_pointer()


def test_check_env_specs(counter_rom):
    check_env_specs(make(counter_rom), seed=0, break_when_any_done="both")  # rollouts with and without resets


def test_partial_reset_through_the_reset_mask(counter_rom):
    env = make(counter_rom)
    td = env.reset()
    start_screen = td["observation"][0].clone()
    for _ in range(3):
        td = step(env, td)
    assert td["terminated"].squeeze(-1).tolist() == [True, False, False] and td["score"].tolist() == [24, 12, 0]
    stood = step(env, td)  # no autoreset: env 0 stands still, reward 0, still terminated
    assert stood["reward"].squeeze(-1).tolist() == [0.0, 4.0, 0.0] and stood["done"].squeeze(-1).tolist() == [
        True, True, True]
    before = stood["observation"].clone()
    reset = env.reset(stood.set("_reset", torch.tensor([[True], [False], [False]])))
    assert reset["episode_step"].tolist() == [0, 4, 4] and reset["score"].tolist() == [0, 16, 0]
    assert reset["done"].squeeze(-1).tolist() == [False, True, True]
    assert torch.equal(reset["observation"][1:], before[1:])  # rows not reset keep their data
    assert torch.equal(reset["observation"][0], start_screen) and before[0, -1, 24:29].any()
    assert step(env, reset)["reward"].squeeze(-1).tolist() == [8.0, 0.0, 0.0]


def test_an_all_false_reset_mask_changes_nothing(counter_rom):
    env = make(counter_rom)
    td = step(env, env.reset())
    before = td.clone()
    after = env.reset(td.set("_reset", torch.zeros(N, 1, dtype=torch.bool)))
    assert torch.equal(after["observation"], before["observation"]) and after["score"].tolist() == [8, 4, 0]


def test_seed_gives_env_i_seed_plus_i_like_the_vector_env(counter_rom):
    """The digit's x is random (CXNN): equal screens mean equal key chains."""
    env = make(counter_rom)
    env.set_seed(5)
    td = env.reset()
    vector = OctaxVectorEnv(COUNTER, N, rom=counter_rom, autoreset_mode="disabled", max_episode_steps=4)
    obs, _ = vector.reset(seed=5)
    assert np.array_equal(td["observation"].numpy(), obs)
    for _ in range(3):
        td = step(env, td)
        obs, *_ = vector.step(ACTIONS.numpy())
        assert np.array_equal(td["observation"].numpy(), obs)
    env.set_seed(5)
    again = step(env, env.reset())
    vector.reset(seed=5)
    assert np.array_equal(again["observation"].numpy(), vector.step(ACTIONS.numpy())[0])
    with pytest.raises(ValueError, match="seed must be"):
        env.set_seed(-1)


def test_collector_batches(counter_rom):
    env = make(counter_rom)
    env.set_seed(0)
    collector = Collector(env, fixed_policy, frames_per_batch=N * 8, total_frames=N * 16,
                          auto_register_policy_transforms=False)
    batches = list(collector)
    collector.shutdown()
    assert len(batches) == 2 and all(b.batch_size == (N, 8) for b in batches)
    data = batches[0]
    assert data["observation"].dtype == torch.uint8 and data["observation"].shape == (N, 8, 4, 32, 64)
    assert data["next", "reward"].shape == (N, 8, 1) and data["action"].dtype == torch.int64
    # Env 0 ends every 3 steps (terminated), envs 1 and 2 every 4 (truncated): partial resets.
    assert data["next", "episode_step"].tolist() == [[1, 2, 3, 1, 2, 3, 1, 2], [1, 2, 3, 4, 1, 2, 3, 4],
                                                     [1, 2, 3, 4, 1, 2, 3, 4]]
    assert data["next", "terminated"][0, :, 0].tolist() == [False, False, True] * 2 + [False, False]
    assert data["next", "truncated"][1, :, 0].tolist() == [False, False, False, True] * 2
    assert data["next", "reward"][0, :, 0].tolist() == [8.0] * 8
    # "next" at the end of an episode is its last screen (digit at y = 24); the following root
    # observation is the new episode's start-up screen.
    assert data["next", "observation"][0, 2, -1, 24:29].any()
    assert torch.equal(data["observation"][0, 3], data["observation"][0, 0])


def test_refuses_the_keywords_it_sets(counter_rom):
    with pytest.raises(TypeError, match="autoreset_mode"):
        make(counter_rom, autoreset_mode="next_step")
    with pytest.raises(TypeError, match="unknown keyword"):
        make(counter_rom, colour="red")


@pytest.mark.parametrize("mode", ["disabled", "same_step"])
def test_gym_wrapper_over_the_vector_env_matches_the_native_env(counter_rom, mode):
    vector = OctaxVectorEnv(COUNTER, N, rom=counter_rom, autoreset_mode=mode, max_episode_steps=4)
    wrapped = GymWrapper(vector, categorical_action_encoding=True)
    check_env_specs(wrapped, seed=0)
    native = make(counter_rom)
    # GymWrapper.set_seed resets at once (and rollout resets again), ours seeds the next reset:
    # reset(seed=0) is the same on both.
    theirs, ours = (env.rollout(8, fixed_policy, auto_reset=False, tensordict=env.reset(seed=0),
                                break_when_any_done=False) for env in (wrapped, native))
    for key in (("next", "reward"), ("next", "terminated"), ("next", "truncated")):
        assert torch.equal(ours[key], theirs[key]), key
    # Observations match up to each env's first episode end, "next" at the end included (GymWrapper
    # takes it from SAME_STEP's final_obs). Later, SAME_STEP's new episode has drawn from the
    # ending step's key, and its screens (the digit's random x) differ; DISABLED's do not.
    steps = 8 if mode == "disabled" else 3
    for key in ("observation", ("next", "observation")):
        assert torch.equal(ours[key][:, :steps], theirs[key][:, :steps]), key


def test_gym_wrapper_refuses_next_step(counter_rom):
    """Why the native env exists: TorchRL cannot use Gymnasium's default autoreset."""
    with pytest.raises(RuntimeError, match="SAME_STEP or DISABLED"):
        GymWrapper(OctaxVectorEnv(COUNTER, N, rom=counter_rom))


def test_networks_shapes_and_scaling():
    cnn = OctaxCNN(frames=4)
    obs = torch.randint(0, 2, (5, 4, 32, 64), dtype=torch.uint8)
    features = cnn(obs)
    assert features.shape == (5, FEATURES) == (5, 1024) and features.dtype == torch.float32
    assert torch.equal(cnn(obs.float()), features)
    scaled = OctaxCNN(frames=4, obs_scale=255)
    scaled.load_state_dict(cnn.state_dict())
    assert torch.allclose(scaled(obs * 255), features)
    assert cnn(obs.reshape(1, 5, 4, 32, 64)).shape == (1, 5, 1024)
    net = ActorCritic(num_actions=3)
    logits, value = net(obs)
    assert logits.shape == (5, 3) and value.shape == (5, 1)
    assert [m.out_features for m in (net.actor[0], net.critic[0])] == [256, 256]
    with pytest.raises(ValueError, match=r"expects observations \(\.\.\., 4, 32, 64\)"):
        cnn(torch.zeros(5, 4, 64, 32))


def test_the_example_ppo_update_runs_on_a_collector_batch(counter_rom):
    spec = importlib.util.spec_from_file_location("train_torchrl_ppo", EXAMPLE)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    args = example.parse_args(["--num-steps", "4", "--minibatches", "2", "--epochs", "1"])
    env = make(counter_rom)
    agent = example.build_agent(env, env.device)
    loss, advantage = example.make_loss(agent, args)
    optimizer = torch.optim.Adam(loss.parameters(), lr=args.lr)
    collector = Collector(env, agent.get_policy_operator(), frames_per_batch=N * 4, total_frames=N * 4,
                          auto_register_policy_transforms=False)
    data = next(iter(collector))
    collector.shutdown()
    before = [p.detach().clone() for p in agent.parameters()]
    stats = example.ppo_update(data, loss, advantage, optimizer, args)
    assert set(stats) == {"loss_objective", "loss_critic", "loss_entropy"} and all(np.isfinite(list(stats.values())))
    assert "advantage" in data.keys() and data["advantage"].shape == (N, 4, 1)
    assert any(not torch.equal(a, b) for a, b in zip(before, agent.parameters()))
    returns = example.play_episodes(env, fixed_policy, seed=0)
    assert returns.tolist() == [24.0, 16.0, 0.0]


def test_an_out_of_range_action_raises_a_named_error(counter_rom):
    """TorchRL's actions are torch tensors: range-checked on the device, never clamped, raised later."""
    from octax_gym import InvalidActionError

    env = make(counter_rom)
    td = env.reset()
    with pytest.raises(InvalidActionError, match=r"action 7 .*valid actions are 0\.\.2"):
        env.step(td.set("action", torch.tensor([2, 7, 0])))
        env.reset()  # the error surfaces here at the latest if the step's report was not ready,
        env.vector_env.close()  # or, the device still busy, when the env is closed
