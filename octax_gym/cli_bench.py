"""`octax-gym bench`: the Pong throughput benchmark (`octax_gym.bench`) with a progress bar.

The options are defined here once and shared with benchmarks/throughput.py (`bench.main`), so the
command and the script take the same flags and print the same `BENCH throughput` lines.

    octax-gym bench --quick                        N = 64,512, 2 repeats, against octax
    octax-gym bench --mode gym --backend torch --envs 512 --no-octax
"""

from __future__ import annotations

import argparse
import functools
from pathlib import Path

MODES = ("machine", "env", "gym")
BACKENDS = ("numpy", "jax", "torch")
ALL_ENVS, QUICK_ENVS = "1,64,512,2048,8192", "64,512"
ALL_REPEATS, QUICK_REPEATS = 5, 2
DEFAULT_ROM_DIR = "../shared/roms/octax"


def add_commands(commands: argparse._SubParsersAction) -> None:
    """Adds `bench` to the `octax-gym` parser."""
    bench = commands.add_parser(
        "bench", help="env steps per second on Pong, against the octax package",
        description="Throughput on Pong (constant action, 4 frames x 11 instructions a step, best of "
                    "several runs, compile excluded), ours against octax 0.1.1 on the same work. One "
                    "`BENCH throughput` line per N on stdout; the progress bar is on stderr. "
                    "See benchmarks/README.md.")
    add_arguments(bench, progress=True)
    bench.set_defaults(func=functools.partial(_cmd_bench, bench))


def _cmd_bench(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    from octax_gym import bench

    # BenchError is a ValueError and the ROM errors are the store's: `cli.main` reports them.
    return bench.run(check_args(parser, args))


def add_arguments(p: argparse.ArgumentParser, *, progress: bool = False) -> None:
    """The benchmark's options; `progress` is the default of `--progress/--no-progress`."""
    p.add_argument("--mode", choices=MODES, default="machine",
                   help="machine: Machine.run_frames alone; env: octax_core.make('Pong') reset + step, "
                        "observation (4 frames, uint8) and reward included; gym: gym.make_vec("
                        "'octax/Pong-v0') stepped from Python, host conversions included (default machine)")
    p.add_argument("--envs", default=None, help=f"comma-separated batch sizes N (default {ALL_ENVS})")
    p.add_argument("--backend", choices=BACKENDS, default=None,
                   help="gym mode: the arrays the vector env takes and hands out (default numpy)")
    p.add_argument("--steps", type=int, default=100, help="env steps per timed run (default 100)")
    p.add_argument("--repeats", type=int, default=None,
                   help=f"timed runs per N; the best is kept (default {ALL_REPEATS})")
    p.add_argument("--key", type=int, default=1,
                   help="CHIP-8 key held for the whole run, 0..15, or -1 for none (default 1: octax "
                        "Pong's action 0, as in its paper benchmark, and action 1 of octax/Pong-v0)")
    p.add_argument("--devices", type=int, default=1,
                   help="machine and env modes: split the batch over this many XLA host devices "
                        "with shard_map (default 1)")
    p.add_argument("--no-octax", action="store_true", help="skip the octax comparison")
    p.add_argument("--octax-max-envs", type=int, default=0,
                   help="run octax only for N up to this (its compile time grows with N; 0 = no cap)")
    p.add_argument("--quick", action="store_true",
                   help=f"a smoke test: N = {QUICK_ENVS} and {QUICK_REPEATS} repeats, unless --envs "
                        "or --repeats says otherwise")
    p.add_argument("--rom", type=Path, default=None,
                   help=f"Pong ROM file or folder (default: the ROM store, see docs/roms.md, then "
                        f"$OCTAX_ROM_DIR or {DEFAULT_ROM_DIR} from the repository root)")
    p.add_argument("--jsonl", type=Path, default=None, help="also append one JSON object per N to this file")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=progress,
                   help="a progress bar on stderr; stdout stays machine-readable "
                        f"(default {'on' if progress else 'off'})")


def check_args(p: argparse.ArgumentParser, args: argparse.Namespace) -> argparse.Namespace:
    """Fills the --quick defaults and checks the values; `p.error` (exit status 2) on a bad one."""
    envs = args.envs if args.envs is not None else (QUICK_ENVS if args.quick else ALL_ENVS)
    if args.repeats is None:
        args.repeats = QUICK_REPEATS if args.quick else ALL_REPEATS
    try:
        args.envs = [int(n) for n in envs.split(",") if n.strip()]
    except ValueError:
        p.error(f"--envs must be comma-separated positive integers, got {envs!r}")
    if not args.envs or min(args.envs) < 1:
        p.error(f"--envs must be positive integers, got {envs!r}")
    if args.steps < 1 or args.repeats < 1 or args.devices < 1:
        p.error("--steps, --repeats and --devices must be >= 1")
    if not -1 <= args.key <= 15:
        p.error(f"--key must be in -1..15, got {args.key}")
    if args.mode == "gym":
        args.backend = args.backend or "numpy"
        if args.devices != 1:
            p.error("--mode gym runs the vector env on one device: --devices must be 1")
    elif args.backend is not None:
        p.error(f"--backend applies to --mode gym only, not to --mode {args.mode}")
    return args
