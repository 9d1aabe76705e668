"""examples/train_jax_selfplay.py: a tiny self-play run on the TwoCounters test game (both seats,
a pool of past selves, evaluation against random and scripted, checkpoints, the Elo round robin)
writes its CSV, plot and Elo table, changes the params, and is the same twice for one seed; the
Bradley-Terry fit and the match's seat bookkeeping checked by hand.

The run uses a small network (the example's ActorCritic compiles for ~20 s more on a CPU), and the
second run of the determinism check reads the first's compiled programs from JAX's persistent
compilation cache, so the file takes well under a minute on an idle CPU.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
import train_jax_selfplay as sp  # noqa: E402

import octax_core  # noqa: E402
from two_player_games import GOAL, TWO_COUNTERS  # noqa: E402

TIMING = ("wall_s", "env_steps_per_s")
TINY = sp.Config(game="TwoCounters", num_envs=4, num_steps=8, num_minibatches=2, update_epochs=2,
                 total_steps=4 * 8 * 3, eval_every=4 * 8, eval_envs=4, elo_games=4, pool=2, pool_prob=0.5,
                 learning_rate=1e-3)


class Tiny(nn.Module):
    """Block means of the planes and one hidden layer: the example's interface, a fraction of its compile."""

    num_actions: int

    @nn.compact
    def __call__(self, obs):
        b, f = obs.shape[:2]
        x = obs.astype(jnp.float32).reshape(b, f, 8, 4, 8, 8).mean((3, 5)).reshape(b, -1)
        x = nn.relu(nn.Dense(32)(x))
        return nn.Dense(self.num_actions)(x), nn.Dense(1)(x)[:, 0]


@pytest.fixture(scope="module")
def rom(two_counters_rom) -> Path:
    return two_counters_rom


@pytest.fixture(scope="module")
def runs(rom, tmp_path_factory):
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
        summaries = [sp.train(TINY, d, game=TWO_COUNTERS, rom=rom, network=Tiny(3)) for d in out]
    finally:
        for name, value in saved.items():
            jax.config.update(name, value)
    return out, summaries


def _rows(path: Path) -> list[dict]:
    with open(path) as f:
        return list(csv.DictReader(f))


def test_run_writes_csv_plot_checkpoints_and_elo(runs):
    (out, _), (summary, _) = runs
    rows = _rows(out / "progress.csv")
    assert tuple(rows[0]) == sp.CSV_COLUMNS
    assert [int(r["update"]) for r in rows] == [0, 1, 2, 3]
    assert [int(r["step"]) for r in rows] == [0, 32, 64, 96]
    for row in rows:
        for opponent in ("random", "scripted"):  # TwoCounters' scripted player always presses key 2
            assert 0 <= float(row[f"win_vs_{opponent}"]) <= 1
            assert float(row[f"ended_vs_{opponent}"]) == 1.0  # 50-step episodes inside the 50-step cap
    for row in rows[1:]:
        for name in sp.PPO_METRICS + ("train_return_seat0", "train_return_seat1"):
            assert np.isfinite(float(row[name])), name
    assert (out / "learning_curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in (out / "checkpoints").iterdir()) == [
        f"params-u{u:05d}.msgpack" for u in range(4)]
    assert (out / "params.msgpack").stat().st_size > 0

    elo = _rows(out / "elo.csv")
    assert tuple(elo[0]) == sp.ELO_COLUMNS
    assert sorted(r["player"] for r in elo) == sorted([f"update {u}" for u in range(4)] + ["random", "scripted"])
    assert next(float(r["elo"]) for r in elo if r["player"] == "random") == 0.0
    assert all(int(r["games"]) == 5 * TINY.elo_games for r in elo)  # everyone meets the 5 others
    assert sum(int(r["wins"]) for r in elo) == sum(int(r["losses"]) for r in elo)
    assert [float(r["elo"]) for r in elo] == sorted((float(r["elo"]) for r in elo), reverse=True)
    # Pressing 2 every frame wins every race to 24 (a seat scores at most 2 a frame).
    scripted = next(r for r in elo if r["player"] == "scripted")
    assert scripted["elo"] == elo[0]["elo"] and float(scripted["score"]) >= 0.9
    assert summary["elo_rows"][0]["player"] == "scripted"


def test_params_change_and_losses_are_finite(runs):
    (out, _), (summary, _) = runs
    first = summary["checkpoints"][0].read_bytes()
    assert first != summary["checkpoints"][-1].read_bytes()
    assert summary["params"].read_bytes() == summary["checkpoints"][-1].read_bytes()


def test_same_seed_same_csv_and_elo(runs):
    (out_a, out_b), _ = runs
    a, b = _rows(out_a / "progress.csv"), _rows(out_b / "progress.csv")
    assert [{k: v for k, v in r.items() if k not in TIMING} for r in a] == \
        [{k: v for k, v in r.items() if k not in TIMING} for r in b]
    assert (out_a / "elo.csv").read_text() == (out_b / "elo.csv").read_text()
    assert (out_a / "params.msgpack").read_bytes() == (out_b / "params.msgpack").read_bytes()


def test_match_seats_and_scores(rom):
    """Scripted (always key 2: +2 a frame, 8 a step) against a player that holds no key: A wins
    every game from either seat, 24 - 0 once the race ends (3 steps)."""
    env, env_params = octax_core.make_multi(TWO_COUNTERS, rom=rom, autoreset=False)
    idle = lambda params, key, obs, state, seat, legal: jnp.zeros(obs.shape[0], jnp.int32)  # noqa: E731
    match = sp.make_match(env, env_params, 4, 10, (sp.scripted_player(env), idle))
    ra, rb, ended = jax.device_get(match(jnp.int32(0), None, jnp.int32(1), None, jax.random.key(0)))
    assert ended.all()
    np.testing.assert_array_equal(ra, [GOAL] * 4)
    np.testing.assert_array_equal(rb, [0] * 4)
    ra, rb, _ = jax.device_get(match(jnp.int32(1), None, jnp.int32(0), None, jax.random.key(0)))
    np.testing.assert_array_equal(rb, [GOAL] * 4)
    assert sp.match_stats(ra, rb, ended) == {"win": 0.0, "draw": 0.0, "return_diff": -GOAL, "ended": 1.0}


def test_bradley_terry_elo():
    # Two players, even record: equal ratings.
    np.testing.assert_allclose(sp.bradley_terry_elo(np.array([[0, 5], [5, 0]]), np.array([[0, 10], [10, 0]]), 0),
                               [0, 0], atol=1e-6)
    # 3 of 4 (plus the virtual draw: 3.5 of 5): p / (p + 1) = 0.7, 400 log10(7/3) above.
    elo = sp.bradley_terry_elo(np.array([[0, 1], [3, 0]]), np.array([[0, 4], [4, 0]]), 0)
    np.testing.assert_allclose(elo, [0, 400 * np.log10(7 / 3)], rtol=1e-6)
    # A perfect record stays finite, and transitivity orders three players.
    wins = np.array([[0, 4, 4], [0, 0, 4], [0, 0, 0]])
    elo = sp.bradley_terry_elo(wins, 4 * (1 - np.eye(3)), 2)
    assert np.isfinite(elo).all() and elo[0] > elo[1] > elo[2] == 0


def test_config_checks():
    with pytest.raises(ValueError, match="one seed"):
        sp.Config(num_seeds=2).check()
    with pytest.raises(ValueError, match="even"):
        sp.Config(eval_envs=3).check()
    assert sp.Config().batch_size == 2 * sp.Config().num_envs * sp.Config().num_steps


def test_closed_actions_are_never_played():
    """Turn-based games: the seat not to move has only no-op open; masked logits and the random
    player never pick a closed action."""
    legal = jnp.array([[True, True, False, True], [True, False, False, False]] * 8)
    logits = jnp.zeros((16, 4)).at[:, 2].set(50.0)  # the network wants the closed action
    keys = jax.random.split(jax.random.key(0), 8)  # a broken mask shows at once: 50 on the closed action
    for key in keys:
        played = jax.random.categorical(key, sp.masked_logits(logits, legal))
        assert bool(legal[jnp.arange(16), played].all())
        played = sp.random_player(None, key, None, None, None, legal)
        assert bool(legal[jnp.arange(16), played].all())
    tiny = Tiny(4)
    params = tiny.init(jax.random.key(1), jnp.zeros((1, 5, 32, 64), jnp.uint8))
    greedy = sp.network_player(tiny, greedy=True)(params, keys[0], jnp.ones((16, 5, 32, 64), jnp.uint8), None,
                                                  None, legal)
    assert bool(legal[jnp.arange(16), greedy].all())
