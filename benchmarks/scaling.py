"""The octax paper's scaling figure, on this machine: env steps/s against the number of envs N.

Five sides, each run as its own subprocess (one after the other, so each has the machine to
itself and JAX's device count can differ), on Pong:

    octax-gym           `throughput.py --mode env`: the functional env (4-frame uint8 observation,
                        reward, flags) vmapped over N and scanned, one XLA CPU device
    octax-gym, 2 devices  the same with the batch split over two XLA host devices (`--devices 2`)
    octax               the `octax` package's Pong on the same work, in the first side's process
    EnvPool             `envpool.make("Pong-v5", env_type="gymnasium", num_envs=N)`, its C++ thread
                        pool (one thread per core), Atari Pong with its defaults (frame skip 4,
                        84x84 grey, 4 stacked frames), random actions, stepped from Python
    ale-py              `gymnasium.make_vec("ALE/Pong-v5", num_envs=N, vectorization_mode=
                        "vector_entry_point")`: ale-py's own threaded AtariVectorEnv, same defaults

An env step is 4 frames on every side (CHIP-8 Pong: 4 x 11 instructions). Each point reports its
steps/s and the wall time of the timed run it came from. EnvPool and ale-py are benchmark-only
extras (`pip install envpool ale-py`, the `scaling` extra); a side that cannot be imported is
skipped with a line saying so.

    python benchmarks/scaling.py                                  # N = 1 .. 8192, the PNG and the page
    python benchmarks/scaling.py --envs 1,64,512 --sides envpool,ale-py --no-write

Writes docs/scaling.png and docs/scaling.md unless --no-write. One `BENCH scaling side=... n=...
sps=... run_s=...` line per point.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Optional

from harness import REPO_ROOT, bench_line

SIDES = ("octax-gym", "octax-gym-2dev", "octax", "envpool", "ale-py")
LABELS = {"octax-gym": "octax-gym (1 XLA device)", "octax-gym-2dev": "octax-gym (2 XLA devices)",
          "octax": "octax 0.1.1", "envpool": "EnvPool Atari Pong", "ale-py": "ale-py AtariVectorEnv Pong"}
HERE = Path(__file__).resolve().parent


def _throughput(envs: list[int], devices: int, with_octax: bool, octax_max: int, steps: int, repeats: int) -> list[dict]:
    """Runs throughput.py --mode env in a subprocess; returns its JSON rows."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "rows.jsonl"
        command = [sys.executable, str(HERE / "throughput.py"), "--mode", "env", "--envs", ",".join(map(str, envs)),
                   "--steps", str(steps), "--repeats", str(repeats), "--devices", str(devices), "--jsonl", str(out)]
        command += ["--octax-max-envs", str(octax_max)] if with_octax else ["--no-octax"]
        subprocess.run(command, check=True, cwd=REPO_ROOT, stdout=sys.stderr)
        return [json.loads(line) for line in out.read_text().splitlines()]


def _atari_side(side: str, n: int, seconds: float) -> dict:
    """One Atari point, in this process: warm up, then step random actions for about `seconds`."""
    import numpy as np

    if side == "envpool":
        import envpool

        env = envpool.make("Pong-v5", env_type="gymnasium", num_envs=n, batch_size=n, num_threads=os.cpu_count(), seed=0)
        num_actions = env.action_space.n
    else:
        import ale_py
        import gymnasium as gym

        gym.register_envs(ale_py)
        env = gym.make_vec("ALE/Pong-v5", num_envs=n, vectorization_mode="vector_entry_point")
        num_actions = env.single_action_space.n
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = [rng.integers(0, num_actions, n) for _ in range(16)]
    for i in range(5):
        env.step(actions[i % 16])
    steps, t0 = 0, time.perf_counter()
    while steps < 10 or time.perf_counter() - t0 < seconds:
        env.step(actions[steps % 16])
        steps += 1
    elapsed = time.perf_counter() - t0
    env.close()
    return dict(side=side, n=n, steps=steps, sps=round(steps * n / elapsed), run_s=round(elapsed, 3))


def _atari(side: str, envs: list[int], seconds: float) -> list[dict]:
    rows = []
    for n in envs:
        command = [sys.executable, str(HERE / "scaling.py"), "--atari-point", side, "--envs", str(n),
                   "--seconds", str(seconds)]
        done = subprocess.run(command, capture_output=True, text=True, cwd=REPO_ROOT)
        if done.returncode != 0:
            print(f"# {side} n={n} failed: {done.stderr.strip().splitlines()[-1] if done.stderr.strip() else done.returncode}",
                  flush=True)
            continue
        rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
    return rows


def _importable(module: str) -> Optional[str]:
    try:
        __import__(module)
    except Exception as exc:  # noqa: BLE001 - any import failure skips the side
        return f"{type(exc).__name__}: {exc}"
    return None


def collect(args) -> tuple[list[dict], dict[str, float]]:
    """Every side's points, and each side's wall time (its subprocesses, compiles and warm-ups included)."""
    points, walls = [], {}
    ours_envs = args.envs
    if "octax-gym" in args.sides or "octax" in args.sides:
        octax_max = args.octax_max_envs if "octax" in args.sides else 0
        t0 = time.perf_counter()
        for row in _throughput(ours_envs, 1, "octax" in args.sides, octax_max, args.steps, args.repeats):
            run_s = row["n"] * row["steps"] / row["sps"]
            if "octax-gym" in args.sides:
                points.append(dict(side="octax-gym", n=row["n"], steps=row["steps"], sps=row["sps"], run_s=round(run_s, 4)))
            if row.get("octax_sps"):
                points.append(dict(side="octax", n=row["n"], steps=row["steps"], sps=row["octax_sps"],
                                   run_s=round(row["n"] * row["steps"] / row["octax_sps"], 4)))
        walls["octax-gym and octax"] = time.perf_counter() - t0
        print(f"# octax-gym (1 device) and octax: {walls['octax-gym and octax']:.0f} s wall", flush=True)
    if "octax-gym-2dev" in args.sides:
        t0 = time.perf_counter()
        for row in _throughput(ours_envs, 2, False, 0, args.steps, args.repeats):
            points.append(dict(side="octax-gym-2dev", n=row["n"], steps=row["steps"], sps=row["sps"],
                               run_s=round(row["n"] * row["steps"] / row["sps"], 4)))
        walls["octax-gym, 2 devices"] = time.perf_counter() - t0
        print(f"# octax-gym (2 devices): {walls['octax-gym, 2 devices']:.0f} s wall", flush=True)
    for side, module in (("envpool", "envpool"), ("ale-py", "ale_py")):
        if side not in args.sides:
            continue
        if (why := _importable(module)) is not None:
            print(f"# {side} skipped: cannot import {module} ({why}); pip install envpool ale-py", flush=True)
            continue
        t0 = time.perf_counter()
        points += _atari(side, [n for n in args.envs if n <= args.atari_max_envs], args.seconds)
        walls[side] = time.perf_counter() - t0
        print(f"# {side}: {walls[side]:.0f} s wall", flush=True)
    return points, walls


def plot(points: list[dict], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=120)
    for side in SIDES:
        mine = sorted((p for p in points if p["side"] == side), key=lambda p: p["n"])
        if mine:
            ax.plot([p["n"] for p in mine], [p["sps"] for p in mine], marker="o", label=LABELS[side])
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("parallel environments N")
    ax.set_ylabel("env steps per second (4 frames a step)")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)


def page(points: list[dict], walls: dict[str, float], command: str, machine: str) -> str:
    ns = sorted({p["n"] for p in points})
    lines = ["# Scaling: env steps/s against the number of envs", "",
             "Generated by `benchmarks/scaling.py` (do not edit by hand); the figure is [scaling.png](scaling.png).", "",
             f"    {command}", "", f"Machine: {machine}.", "",
             "Each cell: env steps per second, and in brackets the wall time of the timed run it comes from "
             "(octax-gym and octax: the best of the repeats of a jitted 100-step rollout, compile excluded; EnvPool "
             "and ale-py: steps from Python for a few seconds after a warm-up). An env step is 4 frames everywhere. "
             "A blank cell was not run (see the command's caps).", "", "![scaling](scaling.png)", "",
             "| side | " + " | ".join(f"N={n}" for n in ns) + " |", "|---|" + "---|" * len(ns)]
    for side in SIDES:
        cells = {p["n"]: p for p in points if p["side"] == side}
        if cells:
            lines.append(f"| {LABELS[side]} | " + " | ".join(
                f"{cells[n]['sps']:,} ({cells[n]['run_s']:.2f} s)" if n in cells else "" for n in ns) + " |")
    lines += ["", "Wall time of each side's whole run (its process start, compiles, warm-ups and every N): "
              + ", ".join(f"{name} {seconds:.0f} s" for name, seconds in walls.items()) + "."]
    return "\n".join(lines) + "\n"


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", default="1,8,64,512,2048,8192", help="comma-separated N (default 1,8,64,512,2048,8192)")
    parser.add_argument("--sides", default=",".join(SIDES), help=f"comma-separated subset of {','.join(SIDES)}")
    parser.add_argument("--steps", type=int, default=100, help="octax-gym / octax: env steps per timed run")
    parser.add_argument("--repeats", type=int, default=3, help="octax-gym / octax: timed runs, best counts")
    parser.add_argument("--octax-max-envs", type=int, default=2048, help="run octax for N up to this (default 2048)")
    parser.add_argument("--atari-max-envs", type=int, default=2048,
                        help="run EnvPool and ale-py for N up to this (default 2048: each Atari env holds its own emulator)")
    parser.add_argument("--seconds", type=float, default=3.0, help="EnvPool / ale-py: seconds of stepping per point")
    parser.add_argument("--jsonl", type=Path, default=None, help="also append each point, as JSON, to this file")
    parser.add_argument("--no-write", action="store_true", help="do not write docs/scaling.png and docs/scaling.md")
    parser.add_argument("--atari-point", choices=("envpool", "ale-py"), default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    args.envs = [int(n) for n in args.envs.split(",")]
    if args.atari_point:  # the subprocess of one Atari point
        print(json.dumps(_atari_side(args.atari_point, args.envs[0], args.seconds)))
        return 0
    args.sides = [s.strip() for s in args.sides.split(",")]
    unknown = sorted(set(args.sides) - set(SIDES))
    if unknown:
        parser.error(f"unknown side(s) {unknown}; valid: {', '.join(SIDES)}")
    machine = f"{platform.machine()}, {os.cpu_count()} cores, CPU only, Python {platform.python_version()}"
    points, walls = collect(args)
    for point in points:
        print(bench_line("scaling", point), flush=True)
        if args.jsonl:
            with args.jsonl.open("a") as f:
                f.write(json.dumps(point) + "\n")
    if not args.no_write:
        given = list(argv if argv is not None else sys.argv[1:])
        if "--jsonl" in given:  # where a copy of the rows went is not part of what was measured
            del given[given.index("--jsonl"):given.index("--jsonl") + 2]
        command = "python benchmarks/scaling.py " + " ".join(given)
        docs = REPO_ROOT / "docs"
        plot(points, docs / "scaling.png", f"Pong, {machine}")
        (docs / "scaling.md").write_text(page(points, walls, command.strip(), machine))
    return 0


if __name__ == "__main__":
    sys.exit(main())
