"""Data-parallel training (examples/jax_training.py `--devices all`): a PPO run of a few updates on
2 processes x 1 CPU device (JAX's distributed runtime on 127.0.0.1, Gloo) ends with the params of
the same run on 1 process x 2 devices, bit for bit, and with those of 1 device to float tolerance
(the sums over the batch run in another order). Every process runs under a timeout."""

from __future__ import annotations

import csv
import os
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

flax = pytest.importorskip("flax")
import jax  # noqa: E402
import flax.serialization  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
ARGS = ["--game", "Brix", "--num-envs", "8", "--num-steps", "8", "--num-minibatches", "2", "--update-epochs", "1",
        "--total-steps", "256", "--eval-every", "128", "--eval-envs", "2", "--max-episode-steps", "40"]
TIMEOUT_S = 300


def start(out_dir: Path, *extra: str, devices: int = 1):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    if devices > 1:
        env["XLA_FLAGS"] = f"--xla_force_host_platform_device_count={devices}"
    return subprocess.Popen([sys.executable, str(REPO / "examples" / "train_jax_ppo.py"), *ARGS, "--out-dir",
                             str(out_dir), *extra], cwd=REPO, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)


def finish(process) -> str:
    try:
        out, _ = process.communicate(timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        pytest.fail(f"a training process ran past {TIMEOUT_S} s:\n{process.communicate()[0][-3000:]}")
    assert process.returncode == 0, out[-3000:]
    return out


def params(folder: Path):
    return jax.tree.leaves(flax.serialization.msgpack_restore((folder / "params.msgpack").read_bytes()))


def evaluations(folder: Path):
    with open(folder / "progress.csv", newline="") as file:
        return [(row["step"], row["eval_mean_return"], row["pg_loss"], row["v_loss"]) for row in csv.DictReader(file)]


@pytest.mark.slow  # three PPO compiles in subprocesses (~2 minutes); CI's test-slow runs it
def test_two_processes_train_the_params_of_one_process_with_two_devices(tmp_path):
    finish(start(tmp_path / "one"))
    finish(start(tmp_path / "two", "--devices", "all", devices=2))
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        coordinator = f"127.0.0.1:{s.getsockname()[1]}"
    ranks = [start(tmp_path / "multi", "--devices", "all", "--coordinator", coordinator, "--num-processes", "2",
                   "--process-id", str(rank)) for rank in range(2)]
    outputs = [finish(process) for process in ranks]
    assert "Gloo" in "".join(outputs)
    two, multi, one = params(tmp_path / "two"), params(tmp_path / "multi"), params(tmp_path / "one")
    assert all(np.array_equal(a, b) for a, b in zip(two, multi))  # the same program, partitioned the same way
    assert evaluations(tmp_path / "two") == evaluations(tmp_path / "multi")  # written by process 0 alone
    assert all(np.allclose(a, b, rtol=1e-4, atol=1e-4) for a, b in zip(one, two))  # sums in another order


@pytest.mark.slow  # a JAX start-up in a subprocess for one message
def test_a_batch_that_does_not_divide_is_refused(tmp_path):
    out = start(tmp_path / "odd", "--devices", "all", "--num-envs", "3", devices=2).communicate(timeout=TIMEOUT_S)[0]
    assert "num_envs=3 does not divide over the 2 devices" in out
