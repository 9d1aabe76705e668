"""examples/train_jax_pqn.py: the Q-network, Q(lambda) targets by hand, the epsilon schedule, the
command line end to end, and a learning check on an endless Counter (as the PPO example's test)."""

from __future__ import annotations

import csv
import dataclasses
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
import train_jax_pqn as pqn  # noqa: E402

from counter_game import COUNTER  # noqa: E402

# Counter without its end: every step pays 0, 4 or 8 (action 0, 1, 2) until the time limit, so
# the best policy (always 2) scores 8 * 8 = 64 and a uniform one 32 on average.
ENDLESS = dataclasses.replace(COUNTER, id="CounterEndless", terminated_fn=lambda s: jnp.bool_(False),
                              max_episode_steps=8)


def test_q_network_shares_the_ppo_torso_and_has_layer_norm():
    import jax_networks

    obs = jnp.zeros((5, 4, 32, 64), jnp.uint8)
    q_values, params = pqn.QNetwork(num_actions=3).init_with_output(jax.random.key(0), obs)
    assert q_values.shape == (5, 3)
    assert pqn.QNetwork is jax_networks.QNetwork
    layers = params["params"]
    assert set(layers) == {"ConvTorso_0", "Dense_0", "LayerNorm_0", "Dense_1"}
    kernels = [layers["ConvTorso_0"][f"Conv_{i}"]["kernel"].shape for i in range(3)]
    assert kernels == [(8, 4, 4, 32), (4, 4, 32, 64), (3, 3, 64, 64)]  # the PPO example's torso
    assert layers["Dense_0"]["kernel"].shape == (1024, 256) and layers["LayerNorm_0"]["scale"].shape == (256,)


def test_q_lambda_targets_match_a_loop():
    rng = np.random.default_rng(0)
    steps, envs, gamma, lam = 7, 3, 0.9, 0.7
    reward, q_max = rng.normal(size=(steps, envs)), rng.normal(size=(steps, envs))
    done = rng.random((steps, envs)) < 0.3
    last_q = rng.normal(size=envs)
    rollout = (jnp.asarray(reward, jnp.float32), jnp.asarray(done), jnp.asarray(q_max, jnp.float32))
    targets = pqn.q_lambda_targets(*rollout, jnp.asarray(last_q, jnp.float32), gamma, lam)
    # The lambda-return written out as a sum: from step t, the n-step returns bootstrapped with
    # max Q after k steps, weighted (1 - lam) lam^(k-1), the rest of the weight on the last one.
    expected = np.zeros((steps, envs))
    for e in range(envs):
        for t in range(steps):
            value, weight_left, discounted = 0.0, 1.0, 0.0
            for k in range(t, steps):
                discounted += gamma ** (k - t) * reward[k, e]
                if done[k, e]:
                    value += weight_left * discounted
                    break
                bootstrap = last_q[e] if k == steps - 1 else q_max[k + 1, e]
                n_step = discounted + gamma ** (k - t + 1) * bootstrap
                if k == steps - 1:
                    value += weight_left * n_step
                else:
                    value += weight_left * (1 - lam) * n_step
                    weight_left *= lam
            expected[t, e] = value
    np.testing.assert_allclose(targets, expected, rtol=1e-5, atol=1e-5)
    # lam = 0: one-step Q-learning targets.
    one_step = pqn.q_lambda_targets(*rollout, jnp.asarray(last_q, jnp.float32), gamma, 0.0)
    next_q = np.concatenate([q_max[1:], last_q[None]])
    np.testing.assert_allclose(one_step, reward + gamma * ~done * next_q, rtol=1e-5, atol=1e-5)


def test_epsilon_decays_over_the_first_tenth_then_stays():
    config = pqn.Config(num_envs=8, num_steps=10, num_minibatches=2, total_steps=8 * 10 * 100)
    assert float(config.epsilon(0)) == 1.0
    assert float(config.epsilon(5)) == pytest.approx(1.0 - 0.95 * 0.5)
    assert float(config.epsilon(10)) == pytest.approx(0.05)
    assert float(config.epsilon(99)) == pytest.approx(0.05)


def test_epsilon_greedy():
    q_values = jnp.tile(jnp.array([[0.0, 2.0, 1.0]]), (4000, 1))
    greedy = pqn.epsilon_greedy(q_values, jax.random.key(0), 0.0)
    assert np.all(np.asarray(greedy) == 1)
    uniform = np.asarray(pqn.epsilon_greedy(q_values, jax.random.key(0), 1.0))
    assert np.bincount(uniform, minlength=3) == pytest.approx([4000 / 3] * 3, rel=0.1)
    half = np.asarray(pqn.epsilon_greedy(q_values, jax.random.key(1), 0.3))
    assert np.mean(half == 1) == pytest.approx(0.7 + 0.3 / 3, abs=0.03)


def test_make_train_checks_autoreset(counter_rom):
    config = pqn.Config(num_envs=8, num_steps=8, num_minibatches=2, total_steps=64)
    env, eval_env, env_params = pqn.make_envs(config, COUNTER, counter_rom)
    with pytest.raises(ValueError, match="autoreset=True"):
        pqn.make_train(config, eval_env, env_params)
    with pytest.raises(ValueError, match="num_seeds"):
        pqn.make_train(dataclasses.replace(config, num_seeds=0), env, env_params)


@pytest.mark.slow  # a whole main() run (30 s); the update and the config checks above run in make test
def test_main_writes_csv_and_plot_per_seed(tmp_path):
    summary = pqn.main(["--game", "Brix", "--num-envs", "4", "--num-steps", "8", "--num-minibatches", "2",
                        "--update-epochs", "1", "--total-steps", "64", "--eval-every", "32", "--eval-envs", "2",
                        "--max-episode-steps", "40", "--num-seeds", "2", "--seed", "5", "--out-dir", str(tmp_path)])
    with open(tmp_path / "progress.csv") as f:
        rows = list(csv.DictReader(f))
    assert tuple(rows[0]) == pqn.CSV_COLUMNS
    assert [(int(r["seed"]), int(r["step"])) for r in rows] == [(5, 0), (6, 0), (5, 32), (6, 32), (5, 64), (6, 64)]
    for row in rows[2:]:
        for name in ("eval_mean_return", "random_mean_return", "env_steps_per_s", "td_loss", "q_mean", "epsilon"):
            assert np.isfinite(float(row[name])), name
    assert float(rows[0]["epsilon"]) == 1.0 and float(rows[-1]["epsilon"]) < 1.0
    assert (tmp_path / "learning_curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in summary["param_paths"]] == ["params-seed5.msgpack", "params-seed6.msgpack"]
    assert summary["env_steps_per_s"] > 0


@pytest.mark.slow  # a long check (>20 s on 2 cores); CI's test-slow runs it
def test_pqn_learns_to_press_2(counter_rom, tmp_path):
    config = pqn.Config(num_envs=16, num_steps=8, num_minibatches=2, total_steps=16 * 8 * 40,
                        learning_rate=1e-3, eval_every=0, eval_envs=32, eval_epsilon=0.0)
    summary = pqn.train(config, tmp_path, game=ENDLESS, rom=counter_rom, progress=False)
    assert summary["random_mean_return"] == pytest.approx(32, abs=6)
    assert summary["final_eval_mean_return"] > 56  # the greedy policy presses 2 nearly always
