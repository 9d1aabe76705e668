"""`octax-gym bench [ARGS ...]`: runs benchmarks/throughput.py of a source checkout, progress bar on.

The benchmark harness and the octax comparison are dev tools, so they live in the repository's
`benchmarks/` folder, not in the library; this command is a thin door to them for a checkout
(`make` and `pip install -e .` use one). Every argument goes to the script unchanged:

    octax-gym bench --quick                        N = 64,512, 2 repeats, against octax
    octax-gym bench --mode gym --backend torch --envs 512 --no-octax
    octax-gym bench --help                         the script's options
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
SCRIPT = "throughput"


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
    """Imports benchmarks/<name>.py and returns its `main(argv, prog=..., progress=True)`.

    Raises:
        FileNotFoundError: no benchmarks/ folder beside the installed package (a wheel install).
    """
    script = BENCHMARKS / f"{name}.py"
    if not script.is_file():
        raise FileNotFoundError(
            f"octax-gym bench runs {script.relative_to(BENCHMARKS.parent)} of a source checkout, and there is "
            f"none beside this install ({BENCHMARKS}); clone the repository and run `make bench` there")
    if str(BENCHMARKS) not in sys.path:
        sys.path.insert(0, str(BENCHMARKS))  # the scripts import their harness as a sibling module
    return importlib.import_module(name).main(argv, prog="octax-gym bench", progress=True)
