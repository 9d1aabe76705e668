"""The sharded vector env (`devices="all"`) in three layouts: 1 process x 1 device, 1 process x 2
devices, 2 processes x 1 device (JAX's distributed runtime on 127.0.0.1, Gloo collectives).

Each layout runs in fresh processes (XLA fixes the device count at start-up): the global batch of
`--envs` envs of `--game` is reset, warmed up, then stepped `--steps` times with uniform random
actions drawn on the host (numpy in, numpy out: what a Gymnasium user does). The global env
steps/s of a layout is envs x steps over the slowest process's wall time. On this 2-core machine
the ceiling is two cores whatever the layout: the point is that each layout works and what it costs
(the collectives of a step's batch-wide decisions, the host round trip of each process's lanes).
One ``BENCH distributed`` line per layout; the octax package has no sharded env, so no octax side.

    python benchmarks/distributed.py                      # Pong, 512 envs, 100 steps
    python benchmarks/distributed.py --game Brix --envs 64
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Optional

from harness import bench_line, load_average

HERE = Path(__file__).resolve()
LAYOUTS = (("1x1", 1, 1), ("1x2", 1, 2), ("2x1", 2, 1))  # name, processes, devices per process


def worker(args) -> None:
    """One process of a layout: prints a JSON line with its lanes' count and its timed seconds."""
    if args.processes > 1:
        import octax_gym.distributed
        octax_gym.distributed.initialize(args.coordinator, args.processes, args.rank, timeout_s=120)
    import gymnasium as gym
    import numpy as np

    import octax_gym

    gym.register_envs(octax_gym)
    envs = gym.make_vec(f"octax/{args.game}-v0", num_envs=args.envs, devices="all")
    rng = np.random.default_rng(args.rank)
    envs.reset(seed=0)
    for _ in range(5):  # compile and warm up
        envs.step(rng.integers(0, envs.single_action_space.n, envs.num_envs))
    start = time.perf_counter()
    for _ in range(args.steps):
        envs.step(rng.integers(0, envs.single_action_space.n, envs.num_envs))
    seconds = time.perf_counter() - start
    print(json.dumps({"rank": args.rank, "lanes": int(envs.num_envs), "seconds": seconds}), flush=True)


def run_layout(name: str, processes: int, devices: int, args) -> dict:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE.parent.parent), os.environ.get("PYTHONPATH", "")])}
    if devices > 1:
        env["XLA_FLAGS"] = f"--xla_force_host_platform_device_count={devices}"
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        coordinator = f"127.0.0.1:{s.getsockname()[1]}"
    procs = [subprocess.Popen([sys.executable, str(HERE), "--worker", "--game", args.game, "--envs", str(args.envs),
                               "--steps", str(args.steps), "--processes", str(processes), "--rank", str(rank),
                               "--coordinator", coordinator], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for rank in range(processes)]
    results = []
    for proc in procs:
        try:
            out, err = proc.communicate(timeout=args.timeout)
        except subprocess.TimeoutExpired:
            for p in procs:
                p.kill()
            raise SystemExit(f"layout {name}: a process ran past {args.timeout} s")
        if proc.returncode:
            raise SystemExit(f"layout {name}: a process failed:\n{err[-2000:]}")
        results.append(json.loads(out.strip().splitlines()[-1]))
    seconds = max(r["seconds"] for r in results)
    return {"layout": name, "processes": processes, "devices_per_process": devices, "game": args.game,
            "envs": args.envs, "steps": args.steps, "lanes_per_process": results[0]["lanes"],
            "sps": round(args.envs * args.steps / seconds), "load": f"{load_average():.2f}"}


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--game", default="Pong")
    parser.add_argument("--envs", type=int, default=512, help="global batch (default 512; divisible by 2)")
    parser.add_argument("--steps", type=int, default=100, help="timed steps (default 100)")
    parser.add_argument("--timeout", type=int, default=600, help="seconds a layout may take (default 600)")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--processes", type=int, default=1, help=argparse.SUPPRESS)
    parser.add_argument("--rank", type=int, default=0, help=argparse.SUPPRESS)
    parser.add_argument("--coordinator", default="", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker(args)
        return 0
    if args.envs < 2 or args.envs % 2 or args.steps < 1:
        parser.error("--envs must be even and >= 2, --steps >= 1")
    print(f"# {args.game}, {args.envs} envs, {args.steps} steps per layout, cpus={os.cpu_count()}")
    for name, processes, devices in LAYOUTS:
        print(bench_line("distributed", run_layout(name, processes, devices, args)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
