"""What a fresh Python process pays before it does anything: `import octax_gym`, and the CLI's
`octax-gym --version`, against the octax package's `import octax` (both import JAX first).

Every CLI command, every worker of a multi-process run, and every test that starts a process pays
this, so it is watched here: ml_dtypes 0.7.0 (a JAX dependency) once put a second of NumPy ufunc
registration into it (pyproject.toml keeps it below 0.7; docs/machine-log.md). Each case is timed
as the wall time of a whole `python -c ...` subprocess, best of `--repeats`, the cases alternating.

    python benchmarks/startup.py              # one BENCH startup line
    python benchmarks/startup.py --repeats 9

One `BENCH startup ...` line: the best wall seconds of each case, the ml_dtypes and numpy
versions, and `ratio` = octax's import over ours (above 1: ours starts faster).
"""

from __future__ import annotations

import argparse
import importlib.metadata
import os
import platform
import subprocess
import sys
import time

from harness import bench_line, load_average

CASES = {
    "import_octax_gym": [sys.executable, "-c", "import octax_gym"],
    "cli_version": [sys.executable, "-m", "octax_gym", "--version"],
    "import_octax": [sys.executable, "-c", "import octax"],
}


def _version(package: str):
    try:
        return importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        return None


def time_once(command: list[str]) -> float:
    """Wall seconds of one run of `command`; a failure is an error, not a time."""
    start = time.perf_counter()
    result = subprocess.run(command, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if result.returncode != 0:
        raise SystemExit(f"error: {' '.join(command[1:])} failed:\n{result.stderr[-2000:]}")
    return seconds


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5, help="runs of each case; the best counts (default 5)")
    parser.add_argument("--no-octax", action="store_true", help="skip the octax package's import (not installed)")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error(f"--repeats must be at least 1, got {args.repeats}")
    cases = {name: command for name, command in CASES.items() if not (args.no_octax and name == "import_octax")}
    if "import_octax" in cases and _version("octax") is None:
        parser.error("the octax package is not installed (the dev extra has it); pass --no-octax to skip it")
    print(f"# python {platform.python_version()} cpus={os.cpu_count()} jax {_version('jax')} "
          f"ml_dtypes {_version('ml_dtypes')} numpy {_version('numpy')}", flush=True)
    best = {name: float("inf") for name in cases}
    for _ in range(args.repeats):
        for name, command in cases.items():  # alternating, so a slow spell of the machine hits every case
            best[name] = min(best[name], time_once(command))
    fields = {f"{name}_s": f"{seconds:.3f}" for name, seconds in best.items()}
    ratio = best["import_octax"] / best["import_octax_gym"] if "import_octax" in best else None
    fields.update(ratio=None if ratio is None else f"{ratio:.2f}", ml_dtypes=_version("ml_dtypes"),
                  numpy=_version("numpy"), repeats=args.repeats, load=f"{load_average():.2f}")
    print(bench_line("startup", fields))
    return 0


if __name__ == "__main__":
    sys.exit(main())
