"""`octax-gym train bc` and `train cql`: offline training as a configuration of the one loop (a draw
from a Minari dataset instead of a rollout), with its rows, agents and evaluation in the dataset's
env. Trained on a test-sized expert dataset, the agents play better than random.

The expert is a scripted Flak player that fires 90% of the time (random play scores about half of
what steady fire does in 300 steps): a dataset where what to copy is clear, so a hundred gradient
steps on it must beat random, and would not if the draw, the losses or the greedy evaluation were
wrong. Random play here is BC's untrained agent sampled (a near-uniform softmax over the game's
actions) in the same evaluation episodes; the committed random baseline is of whole episodes, not
of these 300-step ones.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("minari")
pytest.importorskip("flax")
from octax_gym.cli import main  # noqa: E402

DATASET = "octax/Flak-fire-v0"
FIRE = 3
# 2 agents x (64 x 4 transitions an update, 4 Adam steps of 64): 100 gradient steps for BC
ARGS = ("--dataset", DATASET, "--num-seeds", "2", "--num-envs", "64", "--num-steps", "4", "--num-minibatches", "4",
        "--update-epochs", "1", "--eval-every", "0", "--eval-envs", "16", "--no-progress")


@pytest.fixture(scope="module")
def minari_dir(tmp_path_factory):
    from octax_gym.datasets import collect_dataset

    folder = tmp_path_factory.mktemp("minari")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(folder))
        rng = np.random.default_rng(0)

        def mostly_fire(obs):
            return np.where(rng.random(len(obs)) < 0.9, FIRE, rng.integers(0, 4, len(obs))).astype(np.int64)

        collect_dataset("Flak", DATASET, 2400, num_envs=8, policy=mostly_fire, progress=False, max_episode_steps=300)
        yield folder


def train(algorithm: str, out: Path, *flags: str) -> list[dict]:
    assert main(["train", algorithm, *ARGS, *flags, "--out-dir", str(out)]) == 0
    with open(out / "progress.csv", newline="") as file:
        return list(csv.DictReader(file))


@pytest.fixture(scope="module")
def bc(minari_dir, tmp_path_factory):
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MINARI_DATASETS_PATH", str(minari_dir))
        out = tmp_path_factory.mktemp("bc") / "run"
        return out, train("bc", out, "--total-steps", str(100 * 64))


def random_play(rows) -> float:
    return float(np.mean([float(r["eval_sampled_return"]) for r in rows if r["step"] == "0"]))


def test_bc_copies_the_expert_and_beats_random(bc):
    out, rows = bc
    assert [(r["game"], r["seed"], r["step"]) for r in rows] == [
        ("Flak", seed, step) for step in ("0", "6400") for seed in ("0", "1")]
    final = [r for r in rows if r["step"] == "6400"]
    assert all(float(r["accuracy"]) > 0.85 for r in final)  # the expert's action, 90% fire
    assert min(float(r["eval_greedy_return"]) for r in final) > 1.3 * random_play(rows), rows
    assert sorted(p.name for p in (out / "agents").iterdir()) == ["Flak-seed0.msgpack", "Flak-seed1.msgpack"]
    config = json.loads((out / "config.json").read_text())
    assert config["games"] == ["Flak"] and ["max_episode_steps", 300] in config["env_overrides"]  # the dataset's env


@pytest.mark.slow  # CQL's update runs the network twice (Q and the target's), and needs more steps
def test_cql_beats_random(bc, minari_dir, tmp_path, monkeypatch):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(minari_dir))
    rows = train("cql", tmp_path / "cql", "--total-steps", str(300 * 64), "--target-every", "25")
    final = [r for r in rows if r["step"] == str(300 * 64)]
    assert min(float(r["eval_greedy_return"]) for r in final) > 1.3 * random_play(bc[1]), rows


@pytest.mark.parametrize("algorithm, flags, message", [
    ("bc", ["--games", "Airplane"], f"{DATASET} is a dataset of Flak, not of Airplane"),
    ("bc", ["--max-episode-steps", "50"], "an offline run plays the env its dataset was collected in"),
    ("bc", ["--target-every", "5"], "--target-every: not a setting of bc (of cql)"),
    ("cql", ["--dataset", "octax/Nothing-v0"], "no Minari dataset 'octax/Nothing-v0'"),
])
def test_bad_offline_flags_are_refused_by_name(algorithm, flags, message, minari_dir, monkeypatch, capsys, tmp_path):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(minari_dir))
    dataset = [] if "--dataset" in flags else ["--dataset", DATASET]
    assert main(["train", algorithm, *dataset, *flags, "--no-progress", "--out-dir", str(tmp_path / "out")]) == 1
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
