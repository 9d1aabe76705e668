"""`octax-gym train` with many agents in one program: `--games Airplane,Deep8 --num-seeds 2` writes a
row per (game, seed, evaluation) and an agent file each, and agent (Deep8, seed 1) learns, bit for
bit, what `--games Deep8 --seed 1` alone learns (rows and params). Both runs are of one algorithm,
`tiny_run.ALGORITHM` (PQN): the rows, the files and the exactness are the loop's and the agent
map's, not an algorithm's (PPO's update is trained by the multi-task and self-play runs)."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

pytest.importorskip("flax")
from tiny_run import ALGORITHM, LONE, STEPS, TOGETHER  # noqa: E402


def rows(out: Path) -> list[dict]:
    with open(out / "progress.csv", newline="") as file:
        return list(csv.DictReader(file))


@pytest.fixture(scope="module")
def together(trained) -> Path:
    return trained(ALGORITHM, *TOGETHER)


def test_a_row_per_game_seed_and_evaluation(together):
    table = rows(together)
    assert [(r["game"], int(r["seed"]), int(r["step"])) for r in table] == [
        (game, seed, step) for step in STEPS for game in ("Airplane", "Deep8") for seed in (0, 1)]
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


def test_an_agent_of_many_learns_what_it_learns_alone(trained):
    """One algorithm's: the exactness is the agent map's (test_parts: one by one is bit exact, for the
    Q network's gradients too), not an algorithm's, so one lone run shows it."""
    together, alone = trained(ALGORITHM, *TOGETHER), trained(ALGORITHM, *LONE)
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
