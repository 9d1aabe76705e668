"""What several `octax-gym` commands share: the registered specs, tables, help.

Every command module imports from here and never from another command module or from the
parser (`octax_gym.cli`), so the command modules form no import circle.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
from pathlib import Path
from typing import Callable

# A ROM file's platform, by the community's file name endings; any other file is read as CHIP-8.
ROM_PLATFORMS = {".ch8": "chip8", ".sc8": "schip", ".xo8": "xochip"}
GAME_OR_ROM_HELP = ("game id (Pong), Gymnasium id (octax/Pong-v0), or the path of a ROM file (.ch8, .sc8 or "
                    ".xo8: all 16 keys, no reward)")


def help_of(parser: argparse.ArgumentParser) -> Callable[[argparse.Namespace], int]:
    """A command function that prints `parser`'s help and returns 2 (bad usage)."""
    def show(_args: argparse.Namespace) -> int:
        parser.print_help()
        return 2
    return show


def game_specs(two_player_only: bool = False) -> list:
    """Every one-player `GameSpec` of the registry (imports it, hence JAX); with `two_player_only`
    also the two-player games that are no one-player env (their ROMs are installed alike)."""
    from octax_core.env.games import get_spec, list_games

    games = list_games()
    if two_player_only:
        games = sorted(set(games) | set(list_games(players=2)))
    return [get_spec(game_id) for game_id in games]


def print_table(rows: list[tuple[str, ...]]) -> None:
    """Left-aligned columns, two spaces apart; the last column is not padded."""
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]) - 1)]
    for row in rows:
        print("  ".join(cell.ljust(w) for cell, w in zip(row, widths)) + "  " + row[-1])


def game_or_rom(name: str) -> tuple:
    """What a command's GAME argument names: (its `GameSpec`, None) for a registered game (its id
    or Gymnasium id, any case), or (a spec made for the file, its path) for a ROM file.

    The one place every command (`info`, `record`, `play`, `trace`) turns a path into a game, so
    a ROM file plays the same everywhere: `octax_core.tools.trace.raw_rom_spec`'s spec (all 16
    keys as actions 1..16, no reward, no end but the step bound), on the platform its ending
    names (`ROM_PLATFORMS`), under an id Gymnasium takes (the file name, other characters `_`).

    Raises:
        UnknownOptionError: neither a game nor a file; the message names the close matches and
            says a ROM path is taken too.
        ValueError: the file is empty or too big to be a program.
    """
    from octax_core.tools.trace import raw_rom_spec
    from octax_gym.envs.choices import UnknownOptionError
    from octax_gym.envs.game_names import resolve_spec

    try:
        return resolve_spec(name), None
    except UnknownOptionError as unknown:
        path = Path(name)
        if not path.is_file():
            endings = ", ".join(ROM_PLATFORMS)
            also = f"{unknown.also}, or the path of a ROM file ({endings}; there is no file {name!r})"
            raise UnknownOptionError(unknown.what, name, unknown.choices, also) from None
    spec = raw_rom_spec(path)
    return dataclasses.replace(spec, id=re.sub(r"[^\w.-]", "_", path.name), quirks=None,
                               platform=ROM_PLATFORMS.get(path.suffix.lower(), "chip8"),
                               description="A ROM file with no game spec: every key is an action, there is no "
                                           "reward, and episodes end only at the step bound."), path
