"""The sharded vector env (`devices="all"`) in three layouts: 1 process x 1 device, 1 process x 2
devices, 2 processes x 1 device (JAX's distributed runtime on 127.0.0.1, Gloo collectives), and
the unsharded env (`plain`, no `devices=`) as the baseline a layout costs against.

Each layout runs in fresh processes (XLA fixes the device count at start-up): the global batch of
`--envs` envs of `--game` is reset, warmed up, then stepped `--steps` times with uniform random
actions drawn on the host (numpy in, numpy out: what a Gymnasium user does). The global env
steps/s of a layout is envs x steps over the slowest process's wall time. On this 2-core machine
the ceiling is two cores whatever the layout: the point is that each layout works and what it costs
(the collectives of a step's batch-wide decisions, the host round trip of each process's lanes).
`--backend jax` or `torch` keeps the observations on the device (a GPU's, by DLPack for torch), as
a trainer on a GPU would; `obs_device` says where they were. Each process then replays its first
steps on the plain env (`gym.make_vec` without `devices=`, the global batch on its one device) with
the same actions and compares its own lanes: `equal` is True when every observation, reward and
flag agrees. One ``BENCH distributed`` line per layout; the octax package has no sharded env, so no
octax side.

    python benchmarks/distributed.py                      # Pong, 512 envs, 100 steps
    python benchmarks/distributed.py --game Brix --envs 64
    python benchmarks/distributed.py --layouts plain,1x1 --backend torch --envs 8192   # one GPU
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
LAYOUTS = {"plain": (1, 1), "1x1": (1, 1), "1x2": (1, 2), "2x1": (2, 1)}  # name: processes, devices per process
CHECKED_STEPS = 20  # steps replayed on the plain env for `equal`


def worker(args) -> None:
    """One process of a layout: prints a JSON line with its lanes' count, its timed seconds, where
    its observations lived, and whether its lanes' first steps equal the plain env's."""
    if args.processes > 1:
        import octax_gym.distributed
        octax_gym.distributed.initialize(args.coordinator, args.processes, args.rank, timeout_s=120)
    import gymnasium as gym
    import numpy as np

    import octax_gym

    gym.register_envs(octax_gym)
    sharded = args.layout != "plain"
    envs = gym.make_vec(f"octax/{args.game}-v0", num_envs=args.envs, backend=args.backend,
                        **({"devices": "all"} if sharded else {}))
    rng = np.random.default_rng(args.rank)
    first = envs.reset(seed=0)
    checked = [first]
    actions = [rng.integers(0, envs.single_action_space.n, envs.num_envs) for _ in range(CHECKED_STEPS)]
    for action in actions[:5]:  # compile and warm up
        checked.append(envs.step(action))
    start = time.perf_counter()
    for _ in range(args.steps):
        out = envs.step(rng.integers(0, envs.single_action_space.n, envs.num_envs))
    _block(out[0])
    seconds = time.perf_counter() - start
    obs_device = _where(out[0])
    equal = None
    if sharded:
        envs.reset(seed=0)  # the same first steps again, against the plain env on this process's device
        checked = [first] + [envs.step(action) for action in actions]
        lanes = np.asarray(envs.global_env_ids)
        plain = gym.make_vec(f"octax/{args.game}-v0", num_envs=args.envs, device=_device_name(envs.device))
        theirs = [plain.reset(seed=0)]
        for action in actions:  # lanes are independent: the other processes' lanes may play anything
            full = np.zeros(args.envs, np.int64)
            full[lanes] = action
            theirs.append(plain.step(full))
        equal = all(np.array_equal(_host(a), np.asarray(b)[lanes])
                    for mine, other in zip(checked, theirs) for a, b in zip(mine[:-1], other[:-1]))
    print(json.dumps({"rank": args.rank, "lanes": int(envs.num_envs), "seconds": seconds,
                      "obs_device": obs_device, "equal": equal}), flush=True)


def _block(x) -> None:
    """Wait for an observation batch the step may still be computing (JAX and torch are async)."""
    if hasattr(x, "block_until_ready"):
        x.block_until_ready()
    elif hasattr(x, "cpu") and getattr(x, "is_cuda", False):
        import torch
        torch.cuda.synchronize(x.device)


def _where(x) -> str:
    if hasattr(x, "devices"):  # a JAX array
        return ",".join(sorted(str(d) for d in x.devices()))
    if hasattr(x, "device") and not isinstance(x, (list, tuple)) and hasattr(x, "is_cuda"):
        return str(x.device)
    return "host"


def _host(x):
    import numpy as np
    if hasattr(x, "cpu") and hasattr(x, "numpy"):  # torch
        return x.cpu().numpy()
    return np.asarray(x)


def _device_name(device) -> str:
    return f"{'cuda' if device.platform == 'gpu' else device.platform}:{device.id}"


def run_layout(name: str, args) -> dict:
    processes, devices = LAYOUTS[name]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE.parent.parent), os.environ.get("PYTHONPATH", "")])}
    if devices > 1:
        env["XLA_FLAGS"] = f"--xla_force_host_platform_device_count={devices}"
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        coordinator = f"127.0.0.1:{s.getsockname()[1]}"
    procs = [subprocess.Popen([sys.executable, str(HERE), "--worker", "--game", args.game, "--envs", str(args.envs),
                               "--steps", str(args.steps), "--processes", str(processes), "--rank", str(rank),
                               "--coordinator", coordinator, "--layout", name, "--backend", args.backend], env=env, stdout=subprocess.PIPE,
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
            "backend": args.backend, "obs_device": results[0]["obs_device"],
            "equal": None if results[0]["equal"] is None else all(r["equal"] for r in results),
            "sps": round(args.envs * args.steps / seconds), "load": f"{load_average():.2f}"}


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--game", default="Pong")
    parser.add_argument("--envs", type=int, default=512, help="global batch (default 512; divisible by 2)")
    parser.add_argument("--steps", type=int, default=100, help="timed steps (default 100)")
    parser.add_argument("--timeout", type=int, default=600, help="seconds a layout may take (default 600)")
    parser.add_argument("--layouts", default="1x1,1x2,2x1",
                        help=f"comma-separated, of {','.join(LAYOUTS)} (default 1x1,1x2,2x1)")
    parser.add_argument("--backend", default="numpy", choices=("numpy", "jax", "torch"),
                        help="what the env hands back (default numpy; jax and torch stay on the device)")
    parser.add_argument("--layout", default="1x1", help=argparse.SUPPRESS)
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
    layouts = [name.strip() for name in args.layouts.split(",") if name.strip()]
    unknown = [name for name in layouts if name not in LAYOUTS]
    if unknown or not layouts:
        parser.error(f"--layouts: unknown {unknown or 'empty list'}; choose from {', '.join(LAYOUTS)}")
    print(f"# {args.game}, {args.envs} envs, {args.steps} steps per layout, cpus={os.cpu_count()}")
    for name in layouts:
        print(bench_line("distributed", run_layout(name, args)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
