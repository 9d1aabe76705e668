"""`octax-gym train --resume OUT`: a run continued from its checkpoint ends with the params, byte for
byte, and the rows of a run never stopped; the rows a cut run logged after its checkpoint are
dropped, and a run cut short keeps its rows and agents up to its last evaluation."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pytest

pytest.importorskip("flax")
from octax_gym.cli import main  # noqa: E402
from tiny_run import ALGORITHM, LONE, STEPS  # noqa: E402


def table(out: Path) -> list[dict]:
    with open(out / "progress.csv", newline="") as file:
        return [{k: v for k, v in row.items() if k not in ("wall_s", "env_steps_per_s")} for row in csv.DictReader(file)]


@pytest.fixture(scope="module")
def whole(trained) -> Path:
    """The lone run of (Deep8, seed 1) (tiny_run.ALGORITHM; TINY: 6 updates, evaluations and checkpoints every 2)."""
    return trained(ALGORITHM, *LONE)


def test_a_resumed_run_ends_as_the_run_never_stopped(whole, tmp_path):
    cut = tmp_path / "cut"
    shutil.copytree(whole, cut)
    assert json.loads((cut / "resume" / "checkpoint.json").read_text()) == {"update": 4}
    # As if killed just before its end: the checkpoint is at update 4, the last rows and agents
    # are those of update 6; the resumed run must drop the rows after update 4 and redo them.
    (cut / "agents" / "Deep8-seed1.msgpack").write_bytes(b"stale")
    assert main(["train", ALGORITHM, "--resume", str(cut), "--no-progress"]) == 0
    assert table(cut) == table(whole)
    assert [int(r["update"]) for r in table(cut)] == [0, 2, 4, 6]
    assert (cut / "agents" / "Deep8-seed1.msgpack").read_bytes() == (whole / "agents" / "Deep8-seed1.msgpack").read_bytes()


def test_resume_is_refused_for_another_algorithm_or_without_a_checkpoint(whole, tmp_path, capsys):
    other = "ppo" if ALGORITHM != "ppo" else "pqn"
    assert main(["train", other, "--resume", str(whole)]) == 1
    assert f"is a {ALGORITHM} run, not {other}" in capsys.readouterr().err
    bare = tmp_path / "bare"
    bare.mkdir()
    shutil.copy(whole / "config.json", bare / "config.json")
    assert main(["train", ALGORITHM, "--resume", str(bare)]) == 1
    assert "--checkpoint-every" in capsys.readouterr().err


def test_each_evaluation_leaves_its_rows_and_agents(whole):
    rows = table(whole)
    assert [int(r["step"]) for r in rows] == list(STEPS)
    config = json.loads((whole / "config.json").read_text())
    assert config["games"] == ["Deep8"] and config["checkpoint_every"] == 2 and "command" in config
