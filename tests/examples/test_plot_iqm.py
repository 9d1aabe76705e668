"""examples/plot_iqm.py: runs grouped by algorithm, returns normalized per game, IQM across seeds and games."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
import plot_iqm  # noqa: E402

from octax_gym.scores import iqm, normalized_score  # noqa: E402


def write_run(folder: Path, algorithm: str, game: str, returns: dict[int, list[float]]) -> Path:
    folder.mkdir()
    (folder / "config.json").write_text(json.dumps({"algorithm": algorithm, "env_id": game}))
    with open(folder / "progress.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, ["seed", "step", "eval_mean_return"])
        writer.writeheader()
        for step, per_seed in returns.items():
            writer.writerows({"seed": s, "step": step, "eval_mean_return": r} for s, r in enumerate(per_seed))
    return folder


def test_curves_are_the_iqm_of_normalized_returns(tmp_path):
    runs = [write_run(tmp_path / "a", "PQN", "Airplane", {0: [0.0, 1.0, 2.0], 100: [3.0, 4.0, 4.0]}),
            write_run(tmp_path / "b", "PQN", "Deep8", {0: [0.5, 0.0, 1.0], 100: [2.0, 6.0, 3.0], 200: [1.0, 1.0, 1.0]}),
            write_run(tmp_path / "c", "PPO", "Airplane", {0: [0.2, 0.2, 0.2]})]
    result = plot_iqm.curves(runs, reps=200)
    assert [step for step, _ in result["PQN"]] == [0, 100]  # the steps both PQN runs have
    airplane = normalized_score("Airplane", np.array([3.0, 4.0, 4.0]))
    deep8 = normalized_score("Deep8", np.array([2.0, 6.0, 3.0]))
    expected = iqm(np.stack([airplane, deep8], axis=1))
    interval = result["PQN"][1][1]
    assert interval.point == pytest.approx(expected)
    assert interval.low <= interval.point <= interval.high
    ppo = result["PPO"][0][1]
    assert ppo.point == pytest.approx(float(normalized_score("Airplane", 0.2))) and ppo.low == ppo.high


def test_mismatched_runs_are_refused(tmp_path):
    one = write_run(tmp_path / "a", "PQN", "Airplane", {0: [0.0, 1.0]})
    same_game = write_run(tmp_path / "b", "PQN", "Airplane", {0: [0.0, 1.0]})
    fewer_seeds = write_run(tmp_path / "c", "PQN", "Deep8", {0: [0.0]})
    with pytest.raises(ValueError, match="one run folder per game"):
        plot_iqm.curves([one, same_game])
    with pytest.raises(ValueError, match="same number of seeds"):
        plot_iqm.curves([one, fewer_seeds])


def test_main_writes_the_figure(tmp_path, capsys):
    runs = [write_run(tmp_path / "a", "PQN", "Airplane", {0: [0.0, 1.0], 10: [4.0, 4.0]})]
    plot_iqm.main([str(runs[0]), "--out", str(tmp_path / "iqm.png"), "--reps", "50"])
    assert (tmp_path / "iqm.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "PQN step=10 normalized_iqm=" in capsys.readouterr().out
