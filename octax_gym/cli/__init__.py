"""The `octax-gym` command line (also `python -m octax_gym`).

One module per command group, each adding its parsers with `add_commands` and importing only
argparse (and `octax_gym.cli.common`) at module level; heavy work (emulation, video, torch) is
imported inside the commands. This module only wires them up and reports errors.

    octax-gym list [--category C]        every game: Gymnasium id, category, actions, ROM status
    octax-gym info GAME                  one game: actions and keys, spaces, quirks, timers, ROM
    octax-gym record GAME --steps N --out FILE.mp4 [--policy random|noop] [--envs K]
    octax-gym bench [ARGS ...]           benchmarks/throughput.py from a source checkout
    octax-gym trace GAME|ROM [--steps N] [--blind] [--plot FILE.png]   registers: score, lives, game over?
    octax-gym asm FILE.8o [-o FILE.ch8]  assemble Octo source into a ROM (docs/octo.md)
    octax-gym disasm FILE.ch8 [-o FILE.8o]   a ROM back to Octo source that reassembles to it
    octax-gym roms list                  each game's ROM: present?, verified?, where
    octax-gym roms install [--dest DIR]  get the octax==0.1.1 wheel with pip, install its ROMs
    octax-gym roms import PATH [--dest DIR]   the same from a folder, zip or wheel on disk
    octax-gym dataset collect GAME --dataset-id ID --steps N [--envs K]   a Minari dataset (docs/datasets.md)
    octax-gym play GAME [--agent PATH] [--record ID] [--port N]   play in the browser (docs/play.md)
"""

from __future__ import annotations

import argparse
import sys
import zipfile
from typing import Optional, Sequence

from octax_gym.cli import bench, dataset, games, octo, play, record, roms, trace


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Runs the command line; returns the exit status (0 ok, 1 failed, 2 bad usage)."""
    parser = build_parser()
    # `bench` hands all its arguments to a script with its own parser; every other command's
    # arguments are checked here.
    args, extra = parser.parse_known_args(argv)
    if getattr(args, "takes_extra_args", False):
        args.extra_args = extra
    elif extra:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    if not hasattr(args, "func"):
        parser.print_help()
        return 2
    from octax_core.env import romstore  # after parsing: it imports JAX

    try:
        return args.func(args)
    except (romstore.RomNotFoundError, romstore.RomHashError, romstore.RomInstallError,
            OSError, ValueError, ImportError, zipfile.BadZipFile) as exc:
        print(f"octax-gym: error: {exc}", file=sys.stderr)
        return 1


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="octax-gym", description="CHIP-8, SUPER-CHIP and XO-CHIP games as reinforcement-learning environments.")
    commands = parser.add_subparsers(title="commands", metavar="COMMAND")
    for module in (games, roms, record, bench, octo, trace, dataset, play):
        module.add_commands(commands)
    return parser


if __name__ == "__main__":
    sys.exit(main())
