"""examples/train_jax_multitask.py: a tiny multi-task run on two test games (Counter, and a
one-key Counter: different action counts) writes its CSV, plot and per-game table, reports every
game, keeps each env on its game, never plays an action outside a game's mask, and is the same
twice for one seed; the masked policy checked alone; the normalized scores of real games.

The run uses a small network (the example's CNN compiles for ~20 s more on a CPU), and the second
run of the determinism check reads the first's compiled programs from JAX's persistent
compilation cache, as tests/examples/test_train_jax_selfplay.py does.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import sys
from pathlib import Path

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
import train_jax_multitask as mt  # noqa: E402

import octax_core  # noqa: E402
from counter_game import COUNTER, COUNTER_ROM  # noqa: E402

TIMING = ("wall_s", "env_steps_per_s")
# Counter takes keys 1 and 2 (actions 0, 1, 2); CounterTwo only key 2 (actions 0, 1): in the mix,
# action 2 is outside CounterTwo's mask.
COUNTER_TWO = dataclasses.replace(COUNTER, id="CounterTwo", action_keys=(2,))
GAMES = (COUNTER, COUNTER_TWO)
TINY = mt.Config(games="Counter,CounterTwo", num_envs=8, num_steps=8, num_minibatches=2, update_epochs=2,
                 total_steps=8 * 8 * 2, eval_every=8 * 8, eval_envs=2, learning_rate=1e-3)


class Tiny(nn.Module):
    """Block means of the frames plus the game's one-hot, one hidden layer: the example's
    interface ((frames, game) -> logits, values), a fraction of its compile."""

    num_actions: int

    @nn.compact
    def __call__(self, obs):
        frames, game = obs
        b, f = frames.shape[:2]
        x = frames.astype(jnp.float32).reshape(b, f, 8, 4, 8, 8).mean((3, 5)).reshape(b, -1)
        x = jnp.concatenate([x, jax.nn.one_hot(game, len(GAMES))], -1)
        x = nn.relu(nn.Dense(32)(x))
        return nn.Dense(self.num_actions)(x), nn.Dense(1)(x)[:, 0]


@pytest.fixture(scope="module")
def roms(tmp_path_factory) -> list[Path]:
    path = tmp_path_factory.mktemp("roms") / "counter.ch8"
    path.write_bytes(COUNTER_ROM)
    return [path, path]


@pytest.fixture(scope="module")
def runs(roms, tmp_path_factory):
    """The same tiny run twice (the second compiles nothing: the persistent cache has it)."""
    cache = tmp_path_factory.mktemp("jax_cache")
    saved = {name: getattr(jax.config, name) for name in (
        "jax_compilation_cache_dir", "jax_persistent_cache_min_compile_time_secs",
        "jax_persistent_cache_min_entry_size_bytes")}
    jax.config.update("jax_compilation_cache_dir", str(cache))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    try:
        out = [tmp_path_factory.mktemp(f"run{i}") for i in range(2)]
        summaries = [mt.train(TINY, d, games=GAMES, roms=roms, progress=False, network=Tiny(3)) for d in out]
    finally:
        for name, value in saved.items():
            jax.config.update(name, value)
    return out, summaries


def _rows(path: Path) -> list[dict]:
    with open(path) as f:
        return list(csv.DictReader(f))


def test_run_writes_csv_plot_and_reports_every_game(runs):
    (out, _), (summary, _) = runs
    rows = _rows(out / "progress.csv")
    assert tuple(rows[0]) == mt.csv_columns(("Counter", "CounterTwo"))
    assert [int(r["update"]) for r in rows] == [0, 1, 2]
    assert [int(r["step"]) for r in rows] == [0, 64, 128]
    for row in rows:
        for game in ("Counter", "CounterTwo"):
            assert np.isfinite(float(row[f"return_{game}"])), game
            assert math.isnan(float(row[f"norm_{game}"]))  # test games have no reference score
    for row in rows[1:]:
        for name in mt.PPO_METRICS:
            assert np.isfinite(float(row[name])), name
        # fixed lanes: each game's 4 envs x 8 steps of the update, every update
        assert int(row["train_steps_Counter"]) == int(row["train_steps_CounterTwo"]) == 32
        assert int(row["illegal_actions"]) == 0
    assert (out / "learning_curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "params.msgpack").stat().st_size > 0
    final = _rows(out / "final.csv")
    assert [r["game"] for r in final] == ["Counter", "CounterTwo"]
    assert all(float(r["eval_ended_frac"]) == 1.0 for r in final)  # episodes end by 50 steps, the cap is 50
    assert summary["games"] == ("Counter", "CounterTwo")


def test_same_seed_same_csv_and_params(runs):
    (out_a, out_b), _ = runs
    a, b = _rows(out_a / "progress.csv"), _rows(out_b / "progress.csv")
    assert [{k: v for k, v in r.items() if k not in TIMING} for r in a] == \
        [{k: v for k, v in r.items() if k not in TIMING} for r in b]
    assert (out_a / "final.csv").read_text() == (out_b / "final.csv").read_text()
    assert (out_a / "params.msgpack").read_bytes() == (out_b / "params.msgpack").read_bytes()


def test_masked_policy_never_leaves_a_games_mask(roms):
    mix, env, params = mt.make_envs(TINY, GAMES, roms)
    legal = mt.legal_table(mix)
    assert legal == ((True, True, True), (True, True, False))
    assert mix.num_actions == 3
    # the table is the mix's own action mask
    for g in range(2):
        _, state = mix.reset(jax.random.key(0), params, game=g)
        assert tuple(np.asarray(mix.action_mask(state))) == legal[g]
    network = mt.Masked(Tiny(3), legal)
    games = jnp.arange(512, dtype=jnp.int32) % 2
    frames = jax.random.randint(jax.random.key(1), (512, 4, 32, 64), 0, 2).astype(jnp.uint8)
    net_params = network.init(jax.random.key(2), (frames[:1], games[:1]))
    # a large bias on the closed action: unmasked, it would be chosen almost always
    net_params = jax.tree.map(lambda x: x, net_params)
    net_params["params"]["net"]["Dense_1"]["bias"] = jnp.array([0.0, 0.0, 50.0])
    logits, _ = network.apply(net_params, (frames, games))
    probs = jax.nn.softmax(logits)
    assert float(probs[games == 1, 2].max()) == 0.0
    assert float(probs[games == 0, 2].min()) > 0.99
    act = mt.ppo.policy_act(network)
    for seed in range(4):
        actions = np.asarray(act(net_params, jax.random.key(seed), (frames, games)))
        assert not (actions[np.asarray(games) == 1] == 2).any()
    actions = np.asarray(mt.random_policy(legal)(None, jax.random.key(5), (frames, games)))
    assert not (actions[np.asarray(games) == 1] == 2).any()
    assert set(actions[np.asarray(games) == 0]) == {0, 1, 2}


def test_task_env_keeps_each_env_on_its_game(roms):
    """Fixed lanes: after an episode ends, the env restarts on the same game; redraw draws."""
    mix, env, params = mt.make_envs(dataclasses.replace(TINY, redraw_games=False), GAMES, roms)
    n = 8
    keys = jax.random.split(jax.random.key(0), n)
    obs, state = jax.vmap(env.reset, in_axes=(0, None, 0))(keys, params, mt.lane_games(n, 2))
    step = jax.jit(jax.vmap(env.step, in_axes=(0, 0, 0, None)))
    ended = np.zeros(n, bool)
    for t in range(6):  # action 1: Counter +4 a step, CounterTwo (key 2) +8: both end within 6 steps
        obs, state, _, terminated, truncated, info = step(jax.random.split(jax.random.key(t + 1), n), state,
                                                          jnp.ones(n, jnp.int32), params)
        ended |= np.asarray(terminated | truncated)
        np.testing.assert_array_equal(np.asarray(obs[1]), np.arange(n) % 2)
        np.testing.assert_array_equal(np.asarray(info["game"]), np.arange(n) % 2)
    assert ended.all()


def test_config_checks():
    with pytest.raises(ValueError, match="multiple of the number of games"):
        dataclasses.replace(TINY, num_envs=9).check()
    with pytest.raises(ValueError, match="at least two"):
        dataclasses.replace(TINY, games="Counter").check()
    with pytest.raises(ValueError, match="one seed"):
        dataclasses.replace(TINY, num_seeds=2).check()
    assert mt._join_games(["--games", "Pong", "Brix", "--seed", "1"]) == ["--games", "Pong,Brix", "--seed", "1"]
    assert TINY.steps_per_game == 64


def test_normalized_scores_of_real_games():
    assert mt.normalized("Airplane", 4.0) == pytest.approx(1.0)
    assert mt.normalized("Airplane", 0.3125) == pytest.approx(0.0)
    assert math.isnan(mt.normalized("Tetris", 3.0))  # no reference
    assert math.isnan(mt.normalized("NoSuchGame", 3.0))
    iqm, mean = mt.aggregate([0.0, 1.0, 2.0, 3.0, math.nan])
    assert iqm == pytest.approx(1.5) and mean == pytest.approx(1.5)
    assert all(g in octax_core.list_games() for g in mt.DEFAULT_GAMES)


def test_compare_only_reads_finished_single_runs(runs, tmp_path):
    """--compare-only: the multi-task run's final.csv against single-game runs already on disk
    with the baseline's settings (none trained here); a run with other settings would be retrained."""
    import json
    import shutil

    (out, _), _ = runs
    shutil.copy(out / "final.csv", tmp_path / "final.csv")
    returns = {"Counter": 24.0, "CounterTwo": 16.0}
    for game, value in returns.items():
        single = mt.single_config(TINY, game, 2)
        assert (single.total_steps, single.num_envs, single.eval_every) == (64, 8, 32)
        d = tmp_path / f"single-{game}"
        d.mkdir()
        (d / "config.json").write_text(json.dumps({"algorithm": "PPO", **dataclasses.asdict(single)}, default=str))
        (d / "progress.csv").write_text(f"step,eval_mean_return\n0,1.0\n64,{value}\n")
        assert mt._finished_single_run(d, single) == value
        assert mt._finished_single_run(d, dataclasses.replace(single, num_envs=16)) is None
    summary = mt.compare(TINY, tmp_path, games=GAMES, progress=False)
    rows = _rows(tmp_path / "comparison.csv")
    assert [r["game"] for r in rows] == ["Counter", "CounterTwo", "IQM", "mean"]
    assert [float(r["single_return"]) for r in rows[:2]] == [24.0, 16.0]
    final = _rows(out / "final.csv")
    assert [float(r["multi_return"]) for r in rows[:2]] == [float(r["eval_return"]) for r in final]
    assert (tmp_path / "comparison.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert summary["comparison_rows"][0]["steps_per_game"] == 64
