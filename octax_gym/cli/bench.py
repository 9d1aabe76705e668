"""`octax-gym bench [ARGS ...]`: runs benchmarks/throughput.py of a source checkout, progress bar on.

The benchmark harness and the octax comparison are dev tools, so they live in the repository's
`benchmarks/` folder, not in the library; this command is a thin door to them for a checkout
(`make` and `pip install -e .` use one). The script runs in a Python process of its own (this
interpreter), so the library never imports from benchmarks/ nor puts it on its sys.path, and the
script's JAX starts fresh: `--devices N` works whatever this process has already run. Every
argument goes to the script unchanged:

    octax-gym bench --quick                        N = 64,512, 2 repeats, against octax
    octax-gym bench --mode gym --backend torch --envs 512 --no-octax
    octax-gym bench --help                         the script's options
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
SCRIPT = "throughput"
# The child's program: the script's `main` as `octax-gym bench` presents it (its name in messages,
# the progress bar on by default), with benchmarks/ on the child's own sys.path for its harness.
_CHILD = ("import sys; sys.path.insert(0, sys.argv[1]); import importlib; "
          "sys.exit(importlib.import_module(sys.argv[2]).main(sys.argv[3:], prog='octax-gym bench', progress=True))")


def add_commands(commands: argparse._SubParsersAction) -> None:
    """Adds `bench`, which takes no options of its own: `octax_gym.cli.main` hands it the rest."""
    bench = commands.add_parser(
        "bench", add_help=False, help="env steps per second on Pong, against the octax package",
        description="Runs benchmarks/throughput.py from this source checkout with the given arguments "
                    "(`octax-gym bench --help` lists them). See benchmarks/README.md.")
    bench.set_defaults(func=_cmd_bench, takes_extra_args=True)


def _cmd_bench(args: argparse.Namespace) -> int:
    return run_script(SCRIPT, args.extra_args)


def run_script(name: str, argv: list[str]) -> int:
    """Runs benchmarks/<name>.py's `main(argv, prog="octax-gym bench", progress=True)` in a child
    Python process (its stdout and stderr are this process's) and returns its exit status.

    Raises:
        FileNotFoundError: no benchmarks/ folder beside the installed package (a wheel install).
    """
    script = BENCHMARKS / f"{name}.py"
    if not script.is_file():
        raise FileNotFoundError(
            f"octax-gym bench runs {script.relative_to(BENCHMARKS.parent)} of a source checkout, and there is "
            f"none beside this install ({BENCHMARKS}); clone the repository and run `make bench` there")
    sys.stdout.flush()
    sys.stderr.flush()
    return subprocess.run([sys.executable, "-c", _CHILD, str(BENCHMARKS), name, *argv], check=False).returncode
