"""A mix of every accepted variant of an archive against a mix of one: compile time and steps/s.

The issue-42 target: the variants are data (a ROM in each env's memory; one score and end for
the family), so the mix of all of them compiles in at most 2x the time of a mix of one and
steps at least 0.7x as fast, at N = 256. Both sides are `benchmarks/mix.py`'s rollout (autoreset,
uniform actions), timed alternately in one process, best of `--repeats`; env i plays variant
i mod K. The make time (booting each variant's ROM and its no-op starts, once per env, outside
the compiled program) is printed beside.

Prints one ``BENCH generated_mix`` line: `variants`, `n`, `one_compile_s`, `all_compile_s`,
`compile_ratio`, `one_sps`, `all_sps`, `speed_ratio`, `one_make_s`, `all_make_s` and `met`
(both targets held).

    octax-gym generate --family dodger --count 64 --seed 0 --out generated/dodger
    python benchmarks/generated_mix.py --archive generated/dodger
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Optional

from harness import BenchError, Progress, bench_line, load_average, time_interleaved
from mix import prepare

COMPILE_TARGET, SPEED_TARGET = 2.0, 0.7


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--archive", required=True, help="a folder `octax-gym generate` wrote")
    parser.add_argument("--split", choices=("train", "test"), help="one split only (default both)")
    parser.add_argument("--include-rejected", action="store_true",
                        help="every variant that assembled, not only the accepted ones (more variants)")
    parser.add_argument("--envs", type=int, default=256, help="batch size N (default 256)")
    parser.add_argument("--steps", type=int, default=50, help="env steps per timed run (default 50)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per side, the best counts (default 3)")
    args = parser.parse_args(argv)
    if args.envs < 1 or args.steps < 1 or args.repeats < 1:
        parser.error("--envs, --steps and --repeats must be >= 1")
    try:
        return run(args)
    except (BenchError, ValueError) as exc:
        print(f"{parser.prog}: error: {exc}", file=sys.stderr)
        return 1


def run(args: argparse.Namespace) -> int:
    import jax
    import jax.numpy as jnp

    import octax_core
    from octax_gym.generated import load_archive

    specs = load_archive(args.archive, args.split, accepted_only=not args.include_rejected)
    n = args.envs
    print(f"# jax {jax.__version__} backend={jax.default_backend()} devices={jax.device_count()} "
          f"variants={len(specs)} n={n}", flush=True)
    started = time.perf_counter()
    one, one_params = octax_core.make_mix(specs[:1], autoreset=True)
    one_make = time.perf_counter() - started
    started = time.perf_counter()
    every, every_params = octax_core.make_mix(specs, autoreset=True)
    all_make = time.perf_counter() - started
    sides = {"one": prepare(one, one_params, n, args.steps, jnp.zeros(n, jnp.int32)),
             "all": prepare(every, every_params, n, args.steps, jnp.arange(n) % len(specs))}
    time_interleaved(sides, args.repeats, Progress(0, False), f"n={n}")
    sps = {name: n * args.steps / side.best_s for name, side in sides.items()}
    compile_ratio = sides["all"].compile_s / sides["one"].compile_s
    speed_ratio = sps["all"] / sps["one"]
    print(f"mix of {len(specs)} variants n={n}: {sps['all']:,.0f} steps/s against {sps['one']:,.0f} for one "
          f"({speed_ratio:.2f}x, target >= {SPEED_TARGET}); compile {sides['all'].compile_s:.1f} s against "
          f"{sides['one'].compile_s:.1f} s ({compile_ratio:.2f}x, target <= {COMPILE_TARGET}); make "
          f"{all_make:.1f} s against {one_make:.1f} s; load {load_average():.2f}", flush=True)
    print(bench_line("generated_mix", {
        "variants": len(specs), "n": n, "steps": args.steps,
        "one_compile_s": round(sides["one"].compile_s, 2), "all_compile_s": round(sides["all"].compile_s, 2),
        "compile_ratio": round(compile_ratio, 3), "one_sps": round(sps["one"]), "all_sps": round(sps["all"]),
        "speed_ratio": round(speed_ratio, 3), "one_make_s": round(one_make, 2), "all_make_s": round(all_make, 2),
        "met": int(compile_ratio <= COMPILE_TARGET and speed_ratio >= SPEED_TARGET), "device": jax.default_backend(),
    }), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
