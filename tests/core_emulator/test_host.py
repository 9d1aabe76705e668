"""`octax_core.limit_cpu_threads` / ``OCTAX_CPU_THREADS``: XLA:CPU's pool sized, the process's
cores given back, the same trajectories, and bad settings refused. Each case is a fresh Python
process, since the pool is sized once per process."""

import json
import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(not hasattr(os, "sched_getaffinity"), reason="needs Linux's sched_setaffinity")

PROBE = r"""
import hashlib, json, os, sys
import jax, jax.numpy as jnp
import octax_core
if sys.argv[1] != "env":
    octax_core.limit_cpu_threads(int(sys.argv[1]))
machine = octax_core.Machine("chip8", quirks="chip8", instructions_per_frame=11)
program = bytes([0xA2, 0x0A, 0xC0, 0x3F, 0xC1, 0x1F, 0xD0, 0x15, 0x12, 0x02, 0xF0, 0x90, 0x90, 0x90, 0xF0])
state = jax.vmap(lambda k: machine.boot(program, k))(jax.random.split(jax.random.key(0), 8))
state = jax.jit(jax.vmap(lambda s: machine.run_frames(s, 0, 30)))(state)
tasks = os.listdir("/proc/self/task")
names = [open(f"/proc/self/task/{t}/comm").read().strip() for t in tasks]
print(json.dumps({
    "pool": names.count("tf_XLAEigen"),
    "cores": len(os.sched_getaffinity(0)),
    "every_thread_all_cores": all(os.sched_getaffinity(int(t)) == os.sched_getaffinity(0) for t in tasks),
    "screens": hashlib.sha256(jax.device_get(state.screen).tobytes()).hexdigest(),
}))
"""


def _probe(threads: str, env_threads=None):
    env = {k: v for k, v in os.environ.items() if k != "OCTAX_CPU_THREADS"}
    if env_threads is not None:
        env["OCTAX_CPU_THREADS"] = env_threads
    done = subprocess.run([sys.executable, "-c", PROBE, threads], env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_one_thread_pool_gives_the_cores_back_and_the_same_run():
    default = _probe("env")
    one = _probe("1")
    from_env = _probe("env", env_threads="1")
    assert default["pool"] == default["cores"]  # JAX's default: a thread per core
    assert one["pool"] == 1 and from_env["pool"] == 1
    for run in (one, from_env):
        assert run["cores"] == default["cores"] and run["every_thread_all_cores"]
        assert run["screens"] == default["screens"]


def test_bad_settings_name_the_problem():
    env = dict(os.environ, OCTAX_CPU_THREADS="two")
    done = subprocess.run([sys.executable, "-c", "import octax_core"], env=env, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode != 0 and "OCTAX_CPU_THREADS must be an int >= 1" in done.stderr and "'two'" in done.stderr
    late = r"""
import jax, octax_core
try:
    octax_core.limit_cpu_threads(0)
except ValueError as exc:
    print("ValueError:", exc)
jax.devices()
try:
    octax_core.limit_cpu_threads(1)
except RuntimeError as exc:
    print("RuntimeError:", exc)
"""
    env = {k: v for k, v in os.environ.items() if k != "OCTAX_CPU_THREADS"}
    done = subprocess.run([sys.executable, "-c", late], env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "ValueError: threads must be an int in 1.." in done.stdout
    assert "RuntimeError: JAX's backends have already started" in done.stdout and "OCTAX_CPU_THREADS=1" in done.stdout
