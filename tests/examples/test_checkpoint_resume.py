"""Preemption: a PPO run of examples/train_jax_ppo.py killed with SIGKILL after its second
checkpoint and resumed with `--resume DIR` ends with the params, byte for byte, and the evaluations
of a run never killed (examples/jax_training.py `Checkpoints`, `train(resume=True)`).

The killed run is a real process, killed from outside at a moment the test does not choose
finely (as soon as its checkpoint.json reports the second checkpoint, while it goes on updating),
so the rows it logged past its checkpoint are on disk too and must be dropped on resume.
"""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("flax")
REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "examples"))
import jax_training  # noqa: E402
import train_jax_ppo as ppo  # noqa: E402

EVERY = 8  # updates between checkpoints and between evaluations
ARGS = ["--game", "Brix", "--num-envs", "4", "--num-steps", "8", "--num-minibatches", "2", "--update-epochs", "1",
        "--total-steps", str(5 * EVERY * 32), "--eval-every", str(EVERY * 32), "--eval-envs", "2",
        "--max-episode-steps", "40", "--checkpoint-every", str(EVERY)]
EVAL_COLUMNS = ("seed", "step", "update", "eval_mean_return", "eval_std", "eval_ended_frac", "random_mean_return",
                "train_episode_return", "train_episodes", "pg_loss", "v_loss", "entropy")


def rows(folder: Path) -> list[dict]:
    with open(folder / "progress.csv", newline="") as file:
        return [{k: row[k] for k in EVAL_COLUMNS} for row in csv.DictReader(file)]


@pytest.mark.slow  # three compiles of the PPO update (~1 minute); CI's test-slow runs it
def test_a_killed_run_resumes_to_the_params_of_a_run_never_killed(tmp_path):
    ppo.main([*ARGS, "--out-dir", str(tmp_path / "whole")])

    killed = tmp_path / "killed"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    process = subprocess.Popen([sys.executable, str(REPO / "examples" / "train_jax_ppo.py"), *ARGS,
                                "--out-dir", str(killed)], cwd=REPO, env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    info = killed / "resume" / "checkpoint.json"
    deadline = time.monotonic() + 300
    try:
        while time.monotonic() < deadline and process.poll() is None:
            if info.is_file() and f'"update": {2 * EVERY}' in info.read_text():
                break
            time.sleep(0.005)
        assert process.poll() is None, "the run ended before its second checkpoint could be seen"
        process.send_signal(signal.SIGKILL)
        assert process.wait(timeout=30) == -signal.SIGKILL
    finally:
        if process.poll() is None:
            process.kill()
    assert not (killed / "params.msgpack").exists()

    summary = ppo.main(["--resume", str(killed)])
    assert (killed / "params.msgpack").read_bytes() == (tmp_path / "whole" / "params.msgpack").read_bytes()
    assert rows(killed) == rows(tmp_path / "whole")  # every evaluation once, as the whole run logged them
    assert summary["final_eval_mean_return"] == pytest.approx(float(rows(killed)[-1]["eval_mean_return"]))


def test_resume_needs_a_checkpoint_and_a_run_folder(tmp_path):
    with pytest.raises(SystemExit, match="config.json"):
        ppo.main(["--resume", str(tmp_path)])
    with pytest.raises(FileNotFoundError, match="--checkpoint-every"):
        jax_training.Checkpoints(tmp_path / "resume").load(None)
    with pytest.raises(ValueError, match="checkpoint_every"):
        jax_training.RunConfig(checkpoint_every=-1).check()
