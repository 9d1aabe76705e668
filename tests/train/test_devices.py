"""`octax-gym train --devices all`: every agent's envs split over the devices (two CPU devices in a
subprocess, `--xla_force_host_platform_device_count=2`) train the params of one device to float
tolerance (sums over the batch run in another order), with the same rows; two processes of one
CPU device each (`--coordinator`, JAX's distributed runtime on 127.0.0.1, Gloo) train the params
of one process with two devices bit for bit; and an env count that does not divide over the
devices is refused by name."""

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
import flax.serialization  # noqa: E402
import jax  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
TIMEOUT_S = 300
ARGS = ["--games", "Airplane,Deep8", "--num-envs", "4", "--num-steps", "8", "--num-minibatches", "2",
        "--update-epochs", "1", "--total-steps", "64", "--eval-every", "32", "--eval-envs", "2", "--eval-max-steps",
        "30", "--max-episode-steps", "20", "--no-progress"]


def start(out: Path, *extra: str, devices: int = 1) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    if devices > 1:
        env["XLA_FLAGS"] = f"--xla_force_host_platform_device_count={devices}"
    return subprocess.Popen([sys.executable, "-m", "octax_gym", "train", "ppo", *ARGS, "--out-dir", str(out), *extra],
                            cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def finish(process: subprocess.Popen) -> subprocess.CompletedProcess:
    try:
        out, err = process.communicate(timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        pytest.fail(f"a training process ran past {TIMEOUT_S} s:\n{process.communicate()[1][-3000:]}")
    return subprocess.CompletedProcess(process.args, process.returncode, out, err)


def run(out: Path, *extra: str, devices: int = 1) -> subprocess.CompletedProcess:
    return finish(start(out, *extra, devices=devices))


def leaves(path: Path):
    return jax.tree.leaves(flax.serialization.msgpack_restore(path.read_bytes()))


def evaluations(out: Path):
    with open(out / "progress.csv", newline="") as file:
        return [(r["game"], r["seed"], r["step"], r["eval_mean_return"]) for r in csv.DictReader(file)]


@pytest.mark.slow  # two trainer start-ups in subprocesses (~1 minute)
def test_two_devices_train_what_one_trains(tmp_path):
    one, two = run(tmp_path / "one"), run(tmp_path / "two", "--devices", "all", devices=2)
    assert one.returncode == 0, one.stderr[-3000:]
    assert two.returncode == 0, two.stderr[-3000:]
    assert evaluations(tmp_path / "one") == evaluations(tmp_path / "two")
    for name in ("Airplane-seed0.msgpack", "Deep8-seed0.msgpack"):
        for a, b in zip(leaves(tmp_path / "one" / "agents" / name), leaves(tmp_path / "two" / "agents" / name)):
            np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-5)


@pytest.mark.slow  # three trainer start-ups in subprocesses (~2 minutes)
def test_two_processes_train_the_params_of_one_process_with_two_devices(tmp_path):
    two = run(tmp_path / "two", "--devices", "all", devices=2)
    assert two.returncode == 0, two.stderr[-3000:]
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        coordinator = f"127.0.0.1:{s.getsockname()[1]}"
    ranks = [start(tmp_path / "multi", "--devices", "all", "--coordinator", coordinator, "--num-processes", "2",
                   "--process-id", str(rank)) for rank in range(2)]
    results = [finish(process) for process in ranks]
    assert all(r.returncode == 0 for r in results), "\n".join(r.stderr[-3000:] for r in results)
    assert "Gloo" in "".join(r.stdout + r.stderr for r in results)
    assert evaluations(tmp_path / "two") == evaluations(tmp_path / "multi")  # written by process 0 alone
    for name in ("Airplane-seed0.msgpack", "Deep8-seed0.msgpack"):  # the same program, partitioned the same way
        for a, b in zip(leaves(tmp_path / "two" / "agents" / name), leaves(tmp_path / "multi" / "agents" / name)):
            np.testing.assert_array_equal(a, b)


@pytest.mark.slow  # a JAX start-up in a subprocess for one message
def test_envs_that_do_not_divide_over_the_devices_are_refused(tmp_path):
    result = run(tmp_path / "odd", "--devices", "all", "--num-envs", "3", "--num-minibatches", "1", devices=2)
    assert result.returncode == 1
    assert "num_envs=3 does not divide over the 2 devices" in result.stderr
