"""examples/train_jax_ppo.py: the network's shapes, GAE by hand, a few updates on the Counter test
game, the command line end to end, and a learning check on an endless Counter."""

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
import train_jax_ppo as ppo  # noqa: E402

from counter_game import COUNTER  # noqa: E402

TINY = ppo.Config(num_envs=8, num_steps=8, num_minibatches=2, update_epochs=2, total_steps=8 * 8 * 3,
                  eval_every=0, eval_envs=4, env_overrides=(("max_episode_steps", 10),))
# Counter without its end: every step pays 0, 4 or 8 (action 0, 1, 2) until the time limit, so
# the best policy (always 2) scores 8 * 8 = 64 and a uniform one 32 on average.
ENDLESS = dataclasses.replace(COUNTER, id="CounterEndless", terminated_fn=lambda s: jnp.bool_(False),
                              max_episode_steps=8)


def test_network_shapes():
    obs = jnp.zeros((5, 4, 32, 64), jnp.uint8)
    features, _ = ppo.ConvTorso().init_with_output(jax.random.key(0), obs)
    assert features.shape == (5, 1024)
    network = ppo.ActorCritic(num_actions=3)
    (logits, value), params = network.init_with_output(jax.random.key(0), obs)
    assert logits.shape == (5, 3) and value.shape == (5,)
    kernels = [params["params"]["ConvTorso_0"][f"Conv_{i}"]["kernel"].shape for i in range(3)]
    assert kernels == [(8, 4, 4, 32), (4, 4, 32, 64), (3, 3, 64, 64)]


@pytest.mark.parametrize("x_shape, k_shape, strides", [
    ((2, 64, 32, 4), (8, 4, 4, 32), (4, 2)), ((2, 15, 15, 32), (4, 4, 32, 64), (2, 2)),
    ((2, 6, 6, 64), (3, 3, 64, 64), (1, 1))])
def test_conv_valid_equals_lax_conv(x_shape, k_shape, strides):
    x = jax.random.normal(jax.random.key(1), x_shape)
    kernel = jax.random.normal(jax.random.key(2), k_shape)
    expected = jax.lax.conv_general_dilated(x, kernel, strides, "VALID",
                                            dimension_numbers=("NHWC", "HWIO", "NHWC"))
    np.testing.assert_allclose(ppo.conv_valid(x, kernel, strides), expected, rtol=1e-4, atol=1e-3)


def test_gae_matches_a_loop():
    rng = np.random.default_rng(0)
    steps, envs, gamma, lam = 6, 3, 0.9, 0.8
    reward, value = rng.normal(size=(steps, envs)), rng.normal(size=(steps, envs))
    done = rng.random((steps, envs)) < 0.3
    last_value = rng.normal(size=envs)
    rollout = (jnp.asarray(reward, jnp.float32), jnp.asarray(done), jnp.asarray(value, jnp.float32))
    advantages, targets = ppo._gae(*rollout, jnp.asarray(last_value, jnp.float32), gamma, lam)
    expected, running = np.zeros((steps, envs)), np.zeros(envs)
    for t in reversed(range(steps)):
        next_value = last_value if t == steps - 1 else value[t + 1]
        delta = reward[t] + gamma * next_value * ~done[t] - value[t]
        running = delta + gamma * lam * ~done[t] * running
        expected[t] = running
    np.testing.assert_allclose(advantages, expected, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(targets, expected + value, rtol=1e-5, atol=1e-5)


def test_updates_run_and_change_params(counter_rom):
    env, _, env_params = ppo.make_envs(TINY, COUNTER, counter_rom)
    trainer = ppo.make_train(TINY, env, env_params)
    runner = jax.jit(trainer.init)(jax.random.key(0))
    before = runner.params
    update = jax.jit(trainer.update)
    episodes = 0
    for _ in range(3):
        runner, metrics = update(runner)
        for name in ("pg_loss", "v_loss", "entropy", "approx_kl", "clip_frac"):
            assert np.isfinite(metrics[name]), name
        episodes += int(metrics["finished_episodes"])
    assert episodes > 0  # 24 steps in 8 envs, episodes of at most 10 steps
    changed = jax.tree.map(lambda a, b: bool(jnp.any(a != b)), before, runner.params)
    assert all(jax.tree.leaves(changed))


def test_make_train_and_evaluate_check_autoreset(counter_rom):
    env, eval_env, env_params = ppo.make_envs(TINY, COUNTER, counter_rom)
    with pytest.raises(ValueError, match="autoreset=True"):
        ppo.make_train(TINY, eval_env, env_params)
    with pytest.raises(ValueError, match="autoreset=False"):
        ppo.make_evaluate(env, env_params, 2, 10, ppo.random_act(3))
    with pytest.raises(ValueError, match="divisible"):
        ppo.make_train(dataclasses.replace(TINY, num_minibatches=3), env, env_params)


@pytest.mark.slow  # a whole main() run (25 s); the update and the config checks above run in make test
def test_main_writes_csv_and_plot(tmp_path):
    summary = ppo.main(["--game", "Brix", "--num-envs", "4", "--num-steps", "8", "--num-minibatches", "2",
                        "--update-epochs", "1", "--total-steps", "64", "--eval-every", "32", "--eval-envs", "2",
                        "--max-episode-steps", "40", "--save-at-evals", "--out-dir", str(tmp_path)])
    with open(tmp_path / "progress.csv") as f:
        rows = list(csv.DictReader(f))
    assert tuple(rows[0]) == ppo.CSV_COLUMNS
    assert [int(r["step"]) for r in rows] == [0, 32, 64]
    for row in rows[1:]:
        for name in ("eval_mean_return", "eval_std", "random_mean_return", "env_steps_per_s", "pg_loss",
                     "v_loss", "entropy"):
            assert np.isfinite(float(row[name])), name
    assert float(rows[-1]["eval_ended_frac"]) == 1.0  # 40-step episodes end inside the 40-step cap
    assert (tmp_path / "learning_curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert summary["env_steps_per_s"] > 0
    # --save-at-evals: the params at every evaluation (the dataset suite's medium policies), the last
    # one the final params
    checkpoints = sorted((tmp_path / "checkpoints").iterdir())
    assert [p.name for p in checkpoints] == ["params-step0.msgpack", "params-step32.msgpack", "params-step64.msgpack"]
    assert (tmp_path / "checkpoints" / "params-step64.msgpack").read_bytes() == (tmp_path / "params.msgpack").read_bytes()
    assert checkpoints[0].read_bytes() != checkpoints[1].read_bytes()


@pytest.mark.slow  # a long check (>20 s on 2 cores); CI's test-slow runs it
def test_ppo_learns_to_press_2(counter_rom, tmp_path):
    config = ppo.Config(num_envs=16, num_steps=8, num_minibatches=2, total_steps=16 * 8 * 25,
                        learning_rate=1e-3, eval_every=0, eval_envs=32)
    summary = ppo.train(config, tmp_path, game=ENDLESS, rom=counter_rom, progress=False)
    assert summary["random_mean_return"] == pytest.approx(32, abs=6)
    assert summary["final_eval_mean_return"] > 52  # the policy presses 2 most of the time
