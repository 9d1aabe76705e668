"""The `octax-gym` command line (also `python -m octax_gym`).

One module per command group, each adding its parsers with `add_commands` and importing only
argparse (and `octax_gym.cli.common`) at module level; heavy work (emulation, video, torch) is
imported inside the commands. This module only wires them up and reports errors.

    octax-gym --version                  the installed version (`octax_gym.__version__`)
    octax-gym list [--category C]        every game: Gymnasium id, category, actions, ROM status
    octax-gym info GAME|ROM              one game: actions and keys, spaces, quirks, timers, ROM
    octax-gym record GAME|ROM --steps N --out FILE.mp4 [--policy random|noop] [--envs K]
    octax-gym bench [ARGS ...]           benchmarks/throughput.py from a source checkout
    octax-gym trace GAME|ROM [--steps N] [--blind] [--plot FILE.png]   registers: score, lives, game over?
    octax-gym asm FILE.8o [-o FILE.ch8]  assemble Octo source into a ROM (docs/octo.md)
    octax-gym disasm FILE.ch8 [-o FILE.8o]   a ROM back to Octo source that reassembles to it
    octax-gym roms list                  each game's ROM: present?, verified?, where
    octax-gym roms install [--dest DIR]  get the octax==0.1.1 wheel with pip, install its ROMs
    octax-gym roms import PATH [--dest DIR]   the same from a folder, zip or wheel on disk
    octax-gym dataset collect GAME --dataset-id ID --steps N [--envs K]   a Minari dataset (docs/datasets.md)
    octax-gym play GAME|ROM [--agent PATH] [--record ID] [--port N]   play in the browser (docs/play.md)
    octax-gym train ppo|pqn [--games G,G] [--num-seeds S] [--preset paper]   agents in pure JAX (docs/training.md)
    octax-gym generate --family F --count N --seed S --out DIR   games from a procedural family, checked, archived
    octax-gym generate --list-families   the families (docs/generate.md)
    octax-gym evaluate GAME --agent A [--opponents ladder|NAME] [--episodes N] [--sampled] [--json]
                                         a two-player agent against the ladder: win rates, Elo (docs/multiplayer.md)

GAME is a game id or Gymnasium id; where it says GAME|ROM a ROM file's path is taken too (all 16
keys, no reward: `octax_gym.cli.common.game_or_rom`).
"""

from __future__ import annotations

import argparse
import os
import stat
import sys
import zipfile
from typing import Optional, Sequence

from octax_gym.cli import bench, dataset, evaluate, games, generate, octo, play, record, roms, trace, train


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
        status = args.func(args)
        sys.stdout.flush()  # here, where a closed pipe is caught, not at exit
        return status
    except BrokenPipeError as exc:
        if _stdout_is_a_pipe():
            return _reader_went_away()
        print(f"octax-gym: error: {exc}", file=sys.stderr)  # some other pipe broke: a real error
        return 1
    except (romstore.RomNotFoundError, romstore.RomHashError, romstore.RomInstallError,
            OSError, ValueError, ImportError, zipfile.BadZipFile) as exc:
        print(f"octax-gym: error: {exc}", file=sys.stderr)
        return 1


def _stdout_is_a_pipe() -> bool:
    try:
        return stat.S_ISFIFO(os.fstat(sys.stdout.fileno()).st_mode)
    except (AttributeError, OSError, ValueError):  # no file behind it (a test's capture), or closed
        return False


def _reader_went_away() -> int:
    """`octax-gym roms list | head`: the reader closed the pipe before the output ended, which is
    no error of ours. As Python's docs advise (signal module, "Note on SIGPIPE"): the rest of
    the output goes to devnull, so the flush at exit cannot raise again, and the exit status is
    1, as for a process that SIGPIPE ends; nothing is printed."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)
    return 1


class _Version(argparse.Action):
    """`--version`: prints `octax_gym.__version__` (the installed distribution's, read in one
    place: `octax_core`) and exits. Looked up only when asked for: the lookup imports JAX."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        from octax_gym import __version__

        print(f"{parser.prog} {__version__}")  # on stdout, as argparse's own "version" action prints
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="octax-gym", description="CHIP-8, SUPER-CHIP and XO-CHIP games as reinforcement-learning environments.")
    parser.add_argument("--version", action=_Version, help="print the installed version and exit")
    commands = parser.add_subparsers(title="commands", metavar="COMMAND")
    for module in (games, roms, record, bench, octo, trace, dataset, play, train, evaluate, generate):
        module.add_commands(commands)
    return parser


if __name__ == "__main__":
    sys.exit(main())
