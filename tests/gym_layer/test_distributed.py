"""A vector env sharded over devices and processes (octax_gym/step/sharding.py, `devices=`), with JAX's
distributed runtime (octax_gym/step/distributed.py): real processes on 127.0.0.1 with CPU collectives
(Gloo), each stepping only its lanes, and every lane equal to the same global env of a plain
single-device env. Every subprocess runs under a timeout, so nothing here can hang.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import jax
import numpy as np
import pytest
from jax.sharding import Mesh

import gymnasium as gym
import octax_gym
from octax_gym.step import sharding

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests"))
import distributed_worker as worker  # noqa: E402

TIMEOUT_S = 240
START_UP_TIMEOUT_S = 90  # a JAX import and a handshake per process, on a loaded 2-core machine


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
    script = ("from octax_gym import distributed\n"  # the 1 s starts after the imports: no load can beat it
              f"try:\n    distributed.initialize('127.0.0.1:{free_port()}', 2, 1, timeout_s=1)\n"
              "except distributed.DistributedInitError as e:\n    print('REFUSED', e)\n")
    out = finish(run(["-c", script]), timeout=120)
    assert "REFUSED process 1 of 2 could not reach the coordinator at 127.0.0.1:" in out and "within 1 s" in out


def join(address: str, num_processes: int, rank: int, timeout_s: int):
    """A process that only joins the run and says how it went: REFUSED and the message, or JOINED."""
    script = ("from octax_gym import distributed\n"
              f"try:\n    distributed.initialize({address!r}, {num_processes}, {rank}, timeout_s={timeout_s})\n"
              "except distributed.DistributedInitError as e:\n    print('REFUSED', e)\n"
              "else:\n    print('JOINED')\n")
    return run(["-c", script])


def refusals(processes, timeout=START_UP_TIMEOUT_S) -> list[str]:
    """Each process's output, every one of them refused by a DistributedInitError (not aborted by JAX)."""
    outs = [finish(process, timeout=timeout) for process in processes]
    for out in outs:
        assert "REFUSED" in out and "JOINED" not in out, out[-3000:]
    return outs



def test_ranks_that_disagree_on_the_process_count_are_refused_on_both_sides():
    address = f"127.0.0.1:{free_port()}"  # rank 0 says 2, rank 1 says 3: JAX joined them silently as 2
    for out in refusals([join(address, 2, 0, 30), join(address, 3, 1, 30)]):
        assert "process 1 says the run has 3 processes, process 0 says 2" in out, out


def test_a_process_id_given_twice_is_refused_on_every_process():
    address = f"127.0.0.1:{free_port()}"
    for out in refusals([join(address, 3, 0, 30), join(address, 3, 1, 30), join(address, 3, 1, 30)]):
        assert "process id 1 is claimed by two processes" in out, out
    address = f"127.0.0.1:{free_port()}"  # two processes 0: the second finds the port held and asks the first
    for out in refusals([join(address, 2, 0, 30), join(address, 2, 0, 30)]):
        assert "process id 0 is claimed by two processes" in out, out


def test_a_port_that_answers_but_is_no_coordinator_is_named_on_every_rank():
    stop = threading.Event()

    def answer_garbage(server):
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except TimeoutError:
                continue
            with conn:
                conn.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n")

    with socket.create_server(("127.0.0.1", 0)) as server:
        server.settimeout(0.2)
        thread = threading.Thread(target=answer_garbage, args=(server,))
        thread.start()
        address = f"127.0.0.1:{server.getsockname()[1]}"
        try:  # a 60 s timeout that is not waited for: a reply that is not the handshake is refused at once
            member, coordinator = refusals([join(address, 2, 1, 60), join(address, 2, 0, 60)], timeout=50)
        finally:
            stop.set()
            thread.join()
    assert f"{address} answered but not with octax-gym's start-up handshake (it sent b'HTTP/1.1 400" in member
    assert f"process 0 could not listen on the coordinator's port" in coordinator, coordinator
    assert "answered but not with octax-gym's start-up handshake" in coordinator, coordinator


def test_process_0_alone_is_refused_after_the_timeout():
    out, = refusals([join(f"127.0.0.1:{free_port()}", 3, 0, 1)])
    assert "process 0 of 3: processes 1, 2 did not join within 1 s" in out, out


def test_where_jax_still_aborts_the_line_before_it_names_the_cause():
    address = f"127.0.0.1:{free_port()}"  # process 1 shakes hands, then stops before JAX's registration
    stops = run(["-c", f"from octax_gym.step import handshake\nprint('MEETING', flush=True)\n"
                       f"handshake.meet({address!r}, 2, 1, timeout_s=30)\n"])
    # Process 0 starts once process 1 waits at the handshake, so its 1 s is all JAX's registration's:
    # no slow import of process 1 can make it a handshake refusal instead.
    assert stops.stdout.readline() == "MEETING\n"
    coordinator = join(address, 2, 0, 1)
    finish(stops, timeout=START_UP_TIMEOUT_S)
    try:
        out, _ = coordinator.communicate(timeout=START_UP_TIMEOUT_S)
    finally:
        coordinator.kill()
    assert coordinator.returncode != 0 and "JOINED" not in out and "REFUSED" not in out, out[-3000:]  # JAX's abort
    warning = ("octax-gym: process 0 of 2 is joining JAX's runtime at " + address + "; if JAX now ends it (SIGABRT, "
               "no Python exception), the likely cause is another process stopped between the start-up handshake")
    assert out.startswith(warning), out[-3000:]


def test_strangers_on_the_port_do_not_fail_the_handshake_and_one_too_many_is_told():
    from octax_gym.step import handshake  # in threads: the handshake alone, without JAX
    port, outcomes = free_port(), {}

    def meet(process_id):
        try:
            handshake.meet(f"127.0.0.1:{port}", 2, process_id, timeout_s=20)
            outcomes[process_id] = "ok"
        except handshake.HandshakeError as exc:
            outcomes[process_id] = str(exc)

    def connect():
        for _ in range(100):  # until the thread's process 0 listens
            try:
                return socket.create_connection(("127.0.0.1", port), timeout=10)
            except ConnectionRefusedError:
                time.sleep(0.1)

    coordinator = threading.Thread(target=meet, args=(0,))
    coordinator.start()
    with connect() as stranger, connect() as late:
        assert stranger.recv(100).startswith(handshake.HANDSHAKE)  # greeted, as a process would be
        stranger.sendall(b"GET / HTTP/1.1\r\n\r\n")  # and dropped: no failure for the run
        member = threading.Thread(target=meet, args=(1,))
        member.start()
        for thread in (member, coordinator):
            thread.join(timeout=40)
        late_lines = b""
        while late_lines.count(b"\n") < 2 and (chunk := late.recv(1000)):
            late_lines += chunk  # greeted, said nothing, and told when the run had all its processes
    assert outcomes == {0: "ok", 1: "ok"}
    assert b"all 2 processes had joined before this one: one process too many" in late_lines, late_lines


def test_bad_start_up_arguments_are_named_before_jax_starts():
    from octax_gym import distributed
    for args, message in [(("127.0.0.1:1", 2, 2), r"process_id must be in 0..num_processes - 1, got process_id=2"),
                          (("127.0.0.1:1", 0, 0), r"num_processes must be an integer >= 1, got 0"),
                          (("127.0.0.1:1", 2, None), r"num_processes and process_id go together"),
                          (("127.0.0.1:1", "2", 1), r"num_processes must be an integer >= 1, got '2'"),
                          (("127.0.0.1:99999", 2, 1), r"port in coordinator_address must be in 1..65535, got 99999"),
                          (("127.0.0.1", 2, 1), r"coordinator_address must be 'host:port', got '127.0.0.1'")]:
        with pytest.raises(ValueError, match=message):
            distributed.initialize(*args, timeout_s=1)
    with pytest.MonkeyPatch.context() as patch:
        for name, value in dict(MASTER_ADDR="127.0.0.1", MASTER_PORT="1", WORLD_SIZE="two", RANK="0").items():
            patch.setenv(name, value)
        with pytest.raises(ValueError, match=r"WORLD_SIZE must be an integer, got 'two'"):
            distributed.initialize()


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
