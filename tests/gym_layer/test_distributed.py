"""A vector env sharded over devices and processes (octax_gym/sharding.py, `devices=`), with JAX's
distributed runtime (octax_gym/distributed.py): real processes on 127.0.0.1 with CPU collectives
(Gloo), each stepping only its lanes, and every lane equal to the same global env of a plain
single-device env. Every subprocess runs under a timeout, so nothing here can hang.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
from pathlib import Path

import jax
import numpy as np
import pytest
from jax.sharding import Mesh

import gymnasium as gym
import octax_gym
from octax_gym import sharding

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests"))
import distributed_worker as worker  # noqa: E402

TIMEOUT_S = 240


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run(args, extra_env=None, timeout=TIMEOUT_S):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
           **(extra_env or {})}
    return subprocess.Popen([sys.executable, *args], cwd=REPO, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)


def finish(process, timeout=TIMEOUT_S) -> str:
    try:
        out, _ = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        out, _ = process.communicate()
        pytest.fail(f"a process did not finish in {timeout} s:\n{out[-3000:]}")
    assert process.returncode == 0, out[-3000:]
    return out


@pytest.fixture(scope="module")
def reference():
    gym.register_envs(octax_gym)
    return worker.play(lambda: gym.make_vec(f"octax/{worker.GAME}-v0", num_envs=worker.NUM_ENVS))


def check_lanes(path: Path, reference) -> np.ndarray:
    got = np.load(path)
    ids = got["ids"]
    for name in ("obs", "reward", "terminated", "truncated", "score"):
        assert np.array_equal(got[name], reference[name][:, ids]), (path.name, name)
    return ids


def test_two_processes_each_step_their_lanes_of_the_global_batch(tmp_path, reference):
    coordinator = f"127.0.0.1:{free_port()}"
    processes = [run([str(REPO / "tests" / "distributed_worker.py"), str(tmp_path / f"rank{rank}.npz"),
                      coordinator, "2", str(rank)]) for rank in range(2)]
    for process in processes:
        finish(process)
    ids = [check_lanes(tmp_path / f"rank{rank}.npz", reference) for rank in range(2)]
    assert [list(i) for i in ids] == [[0, 1], [2, 3]]  # rank r holds lanes 2r, 2r + 1: the global batch once
    for rank in range(2):  # device names resolve to the process's own devices (rank 1's ids are not 0)
        assert np.load(tmp_path / f"rank{rank}.npz")["names_resolve"].all()
    assert reference["terminated"].any()  # episodes ended (and were reset) inside the compared steps


@pytest.mark.slow  # two more JAX start-ups in subprocesses; the 2-process test above runs in `make test`
def test_one_process_with_two_devices_equals_one_device(tmp_path, reference):
    flags = {"XLA_FLAGS": "--xla_force_host_platform_device_count=2"}
    finish(run([str(REPO / "tests" / "distributed_worker.py"), str(tmp_path / "two.npz"), "-", "0", "0"], flags))
    assert list(check_lanes(tmp_path / "two.npz", reference)) == [0, 1, 2, 3]
    script = ("import gymnasium as gym, octax_gym\n"
              "gym.register_envs(octax_gym)\n"
              "try:\n"
              "    gym.make_vec('octax/Brix-v0', num_envs=3, devices='all')\n"
              "except ValueError as e:\n"
              "    print('REFUSED', e)\n")
    out = finish(run(["-c", script], flags))
    assert "REFUSED num_envs=3 does not divide over the 2 devices" in out and "multiple of 2" in out


def test_a_coordinator_that_never_answers_is_a_named_error_not_a_hang():
    script = ("from octax_gym import distributed\n"
              f"try:\n    distributed.initialize('127.0.0.1:{free_port()}', 2, 1, timeout_s=3)\n"
              "except distributed.DistributedInitError as e:\n    print('REFUSED', e)\n")
    out = finish(run(["-c", script]), timeout=120)
    assert "REFUSED process 1 of 2 could not reach the coordinator at 127.0.0.1:" in out and "within 3 s" in out


def test_bad_meshes_and_device_arguments_are_named():
    with pytest.raises(ValueError, match=r"the mesh has axes \('batch',\); the batch is split along one named 'envs'"):
        sharding.Shards(Mesh(np.array(jax.devices()), ("batch",)), 4)
    with pytest.raises(ValueError, match="names a device twice"):
        sharding.Shards(["cpu:0", "cpu:0"], 4)
    with pytest.raises(ValueError, match="devices must be 'all'"):
        sharding.Shards("some", 4)
    with pytest.raises(ValueError, match="not both"):
        octax_gym.OctaxVectorEnv("Brix", 2, device="cpu", devices="all")
    with pytest.raises(ValueError, match="torchrun-style"):
        from octax_gym import distributed
        with pytest.MonkeyPatch.context() as patch:
            patch.setenv("MASTER_ADDR", "127.0.0.1")
            patch.delenv("MASTER_PORT", raising=False)
            distributed.initialize()


def test_one_device_mesh_is_the_plain_env(reference):
    envs = octax_gym.OctaxVectorEnv(worker.GAME, worker.NUM_ENVS, devices="all")
    assert envs.num_envs == envs.global_num_envs == worker.NUM_ENVS and list(envs.global_env_ids) == [0, 1, 2, 3]
    got = worker.play(lambda: envs)
    for name in ("obs", "reward", "terminated", "truncated", "score"):
        assert np.array_equal(got[name], reference[name]), name
