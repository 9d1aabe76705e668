"""examples/train_offline.py: BC and CQL trained on a test-sized expert dataset play better than
random in the batched env, and the command writes its per-seed rows and the IQM summary.

The expert is a scripted Flak player that fires 90% of the time (random play scores about half of
what steady fire does in 300 steps): a dataset where what to copy is clear, so a few hundred
gradient steps on it must beat random, and would not if the loader, the losses or the greedy
evaluation were wrong.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

minari = pytest.importorskip("minari")
pytest.importorskip("optax")

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
import train_offline  # noqa: E402

from octax_gym.datasets import collect_dataset  # noqa: E402

DATASET = "octax/Flak-fire-v0"
FIRE = 3


@pytest.fixture(scope="module")
def expert_dataset(tmp_path_factory):
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(tmp_path_factory.mktemp("minari")))
        rng = np.random.default_rng(0)

        def mostly_fire(obs):
            return np.where(rng.random(len(obs)) < 0.9, FIRE, rng.integers(0, 4, len(obs))).astype(np.int64)

        collect_dataset("Flak", DATASET, 2400, num_envs=8, policy=mostly_fire, progress=False, max_episode_steps=300)
        yield


# CQL's step runs the network twice (Q and the target's), and needs more of them: CI's test-slow runs it.
@pytest.mark.parametrize("algorithm, steps", [("bc", 100), pytest.param("cql", 300, marks=pytest.mark.slow)])
def test_an_offline_agent_beats_random_on_an_expert_dataset(algorithm, steps, expert_dataset, tmp_path):
    summary = train_offline.main(["--algorithm", algorithm, "--dataset-id", DATASET, "--steps", str(steps),
                                  "--num-seeds", "2", "--batch-size", "64", "--eval-envs", "16",
                                  "--log-every", str(steps), "--target-every", "100", "--out-dir", str(tmp_path)])
    rows = (tmp_path / "results.csv").read_text().splitlines()
    assert len(rows) == 3 and rows[0].startswith("game,dataset_id,algorithm,seed,return")
    stored = json.loads((tmp_path / "summary.json").read_text())
    assert stored["algorithm"] == algorithm and set(stored["iqm"]) == {"point", "low", "high"}
    assert stored["iqm"]["low"] <= stored["iqm"]["point"] <= stored["iqm"]["high"]
    returns = [float(row.split(",")[4]) for row in rows[1:]]
    random_return = float(rows[1].split(",")[8])
    assert min(returns) > random_return * 1.3, (returns, random_return)
    assert summary["normalized"]["Flak"] == pytest.approx(stored["normalized"]["Flak"])


def test_bad_flags_are_refused():
    with pytest.raises(SystemExit):
        train_offline.parse_args(["--algorithm", "bcq"])
    with pytest.raises(SystemExit):
        train_offline.parse_args(["--algorithm", "bc", "--steps", "0"])
