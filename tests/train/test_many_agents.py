"""`octax-gym train` with many agents in one program: `--games Airplane,Deep8 --num-seeds 2` writes a
row per (game, seed, evaluation) and an agent file each, and agent (Deep8, seed 1) learns, bit for
bit, what `--games Deep8 --seed 1` alone learns (rows and params), for PPO and PQN."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

pytest.importorskip("flax")
from octax_gym.cli import main  # noqa: E402

TINY = ["--num-envs", "4", "--num-steps", "8", "--num-minibatches", "2", "--update-epochs", "1",
        "--total-steps", "128", "--eval-every", "64", "--eval-envs", "3", "--eval-max-steps", "60",
        "--max-episode-steps", "20", "--no-progress"]


def rows(out: Path) -> list[dict]:
    with open(out / "progress.csv", newline="") as file:
        return list(csv.DictReader(file))


def run(out: Path, algorithm: str, *args: str) -> Path:
    assert main(["train", algorithm, *args, *TINY, "--out-dir", str(out)]) == 0
    return out


@pytest.fixture(scope="module", params=["ppo", "pqn"])
def runs(request, tmp_path_factory):
    folder = tmp_path_factory.mktemp(request.param)
    together = run(folder / "together", request.param, "--games", "Airplane,Deep8", "--num-seeds", "2")
    alone = run(folder / "alone", request.param, "--games", "Deep8", "--seed", "1")
    return together, alone


def test_a_row_per_game_seed_and_evaluation(runs):
    together, _ = runs
    table = rows(together)
    assert [(r["game"], int(r["seed"]), int(r["step"])) for r in table] == [
        (game, seed, step) for step in (0, 64, 128) for game in ("Airplane", "Deep8") for seed in (0, 1)]
    for row in table:
        for column in ("eval_mean_return", "eval_greedy_return", "eval_sampled_return", "random_mean_return",
                       "normalized_score"):
            float(row[column])  # a number in every row
        assert row["eval_mean_return"] == row["eval_sampled_return"]
    # The random baseline is the committed table's, not a measurement (scores.json: Airplane 0.3125).
    assert {float(r["random_mean_return"]) for r in table if r["game"] == "Airplane"} == {0.3125}
    names = sorted(p.name for p in (together / "agents").iterdir())
    assert names == ["Airplane-seed0.msgpack", "Airplane-seed1.msgpack", "Deep8-seed0.msgpack", "Deep8-seed1.msgpack"]
    assert (together / "learning_curve.png").read_bytes()[:4] == b"\x89PNG"
    assert (together / "summary.json").is_file()


def test_an_agent_of_many_learns_what_it_learns_alone(runs):
    together, alone = runs
    mine = [r for r in rows(together) if (r["game"], r["seed"]) == ("Deep8", "1")]
    theirs = rows(alone)
    skip = {"wall_s", "env_steps_per_s"}  # timings
    assert [{k: v for k, v in r.items() if k not in skip} for r in mine] == \
        [{k: v for k, v in r.items() if k not in skip} for r in theirs]
    assert (together / "agents" / "Deep8-seed1.msgpack").read_bytes() == \
        (alone / "agents" / "Deep8-seed1.msgpack").read_bytes()
    # and the agents are not copies of one another
    assert (together / "agents" / "Deep8-seed0.msgpack").read_bytes() != \
        (alone / "agents" / "Deep8-seed1.msgpack").read_bytes()
    assert (together / "agents" / "Airplane-seed1.msgpack").read_bytes() != \
        (alone / "agents" / "Deep8-seed1.msgpack").read_bytes()
