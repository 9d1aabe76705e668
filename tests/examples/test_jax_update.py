"""examples/jax_update.py: the rollout and the minibatch epochs both JAX examples build their update
from, checked on their own (actions reach the envs, the rollout keeps what `act` returns, each
epoch passes over the whole batch), and that PPO and PQN do build on them rather than on copies."""

from __future__ import annotations

import sys
from pathlib import Path

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
import jax_training  # noqa: E402
import jax_update  # noqa: E402
import train_jax_ppo as ppo  # noqa: E402
import train_jax_pqn as pqn  # noqa: E402

from counter_game import COUNTER  # noqa: E402

SHARED = ("make_optimizer", "make_init", "make_rollout", "make_learn")


def _recording(calls: list, name: str, original):
    def recorded(*args, **kwargs):
        calls.append(name)
        return original(*args, **kwargs)

    return recorded


def test_both_examples_build_their_update_from_the_shared_parts(monkeypatch, counter_rom):
    calls = []
    for name in SHARED:
        monkeypatch.setattr(jax_update, name, _recording(calls, name, getattr(jax_update, name)))
    for algorithm in (ppo, pqn):
        config = algorithm.Config(num_envs=2, num_steps=2, num_minibatches=1)
        env, _, env_params = algorithm.make_envs(config, COUNTER, counter_rom)
        calls.clear()
        algorithm.make_train(config, env, env_params)
        assert sorted(calls) == sorted(SHARED), algorithm.__name__


@pytest.mark.parametrize("algorithm, name, runs_dir", [(ppo, "PPO", "runs/jax_ppo"), (pqn, "PQN", "runs/jax_pqn")])
def test_both_command_lines_are_the_shared_main(monkeypatch, algorithm, name, runs_dir):
    seen = []
    monkeypatch.setattr(jax_training, "main", lambda *args: seen.append(args) or "summary")
    assert algorithm.main(["--game", "Brix"]) == "summary"
    (got_name, config_type, make_train, help_text, doc, got_runs_dir, argv), = seen
    assert (got_name, config_type, make_train, help_text, doc, got_runs_dir, argv) == (
        name, algorithm.Config, algorithm.make_train, algorithm.HELP, algorithm.__doc__, runs_dir, ["--game", "Brix"])


class _Tiny(nn.Module):
    @nn.compact
    def __call__(self, obs):
        return nn.Dense(1)(obs.reshape(obs.shape[0], -1).astype(jnp.float32))


def test_rollout_sends_actions_to_the_envs_and_keeps_what_act_returns(counter_rom):
    # Counter pays 4 a step for action 1 and 8 for action 2 and ends at 24: env 0 (action 1) is
    # cut by the 4-step limit after step 3, env 1 (action 2) ends by itself after step 2.
    config = jax_training.RunConfig(num_envs=2, num_steps=5, num_minibatches=1,
                                    env_overrides=(("max_episode_steps", 4),))
    env, _, env_params = jax_training.make_envs(config, COUNTER, counter_rom)
    init = jax_update.make_init(config, env, env_params, _Tiny(), optax.sgd(0.1))

    def act(params, key, obs, actions):
        return actions, {"tagged": actions * 10, "pixels": obs.reshape(obs.shape[0], -1).sum(axis=1)}

    def bootstrap(params, obs):
        return jnp.full(2, 100.0)

    rollout = jax.jit(jax_update.make_rollout(config, env, env_params, act, bootstrap))
    start = init(jax.random.key(0))
    runner, traj = rollout(start, jnp.array([1, 2]))

    assert traj.obs.shape == (5, 2, 4, 32, 64) and traj.obs.dtype == jnp.uint8
    for field in (traj.action, traj.policy_out["tagged"], traj.reward, traj.done, traj.finished_return):
        assert field.shape == (5, 2)
    np.testing.assert_array_equal(traj.obs[0], start.obs)  # what the policy saw, step by step
    np.testing.assert_array_equal(traj.policy_out["tagged"], [[10, 20]] * 5)
    np.testing.assert_array_equal(traj.policy_out["pixels"], traj.obs.reshape(5, 2, -1).sum(axis=2))
    # The truncated step is credited gamma * bootstrap; the terminated one is not.
    np.testing.assert_allclose(traj.reward, [[4, 8], [4, 8], [4, 8], [4 + 0.99 * 100, 8], [4, 8]])
    np.testing.assert_array_equal(traj.done, [[False, False], [False, False], [False, True], [True, False],
                                              [False, False]])
    np.testing.assert_array_equal(traj.finished_return, [[0, 0], [0, 0], [0, 24], [16, 0], [0, 0]])
    np.testing.assert_array_equal(runner.episode_return, [4, 16])  # one and two steps into the next episodes
    assert int(runner.updates) == 0 and not np.array_equal(jax.random.key_data(runner.key),
                                                          jax.random.key_data(start.key))
    assert jax_update.episode_totals(traj) == {"finished_return_sum": 40, "finished_episodes": 2}


def test_learn_passes_over_the_whole_rollout_each_epoch_and_counts_the_update():
    config = jax_training.RunConfig(num_envs=3, num_steps=4, num_minibatches=3, update_epochs=2, learning_rate=0.1)
    batch = jnp.arange(12.0).reshape(4, 3)  # (num_steps, num_envs)

    def loss(params, minibatch):
        return jnp.mean((params["w"] - minibatch) ** 2), {"mean": minibatch.mean(), "size": minibatch.size}

    optimizer = jax_update.make_optimizer(config)
    params = {"w": jnp.zeros(())}
    runner = jax_update.RunnerState(params, optimizer.init(params), None, None, None, jax.random.key(0), jnp.int32(0))
    learned, stats = jax.jit(jax_update.make_learn(config, optimizer, loss))(runner, batch)
    # Every epoch splits all 12 samples into 3 minibatches of 4, so their means average to the batch's.
    assert float(stats["mean"]) == pytest.approx(5.5) and float(stats["size"]) == 4
    assert 0 < float(learned.params["w"]) <= 6 * 0.1 + 1e-6  # 6 Adam steps of at most lr each, towards 5.5
    assert int(learned.updates) == 1
    assert not np.array_equal(jax.random.key_data(learned.key), jax.random.key_data(runner.key))
