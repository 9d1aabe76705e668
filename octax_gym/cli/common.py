"""What several `octax-gym` commands share: the registered specs, tables, help.

Every command module imports from here and never from another command module or from the
parser (`octax_gym.cli`), so the command modules form no import circle.
"""

from __future__ import annotations

import argparse
from typing import Callable


def help_of(parser: argparse.ArgumentParser) -> Callable[[argparse.Namespace], int]:
    """A command function that prints `parser`'s help and returns 2 (bad usage)."""
    def show(_args: argparse.Namespace) -> int:
        parser.print_help()
        return 2
    return show


def game_specs() -> list:
    """Every registered `GameSpec` (imports the registry, hence JAX)."""
    from octax_core.env.games import get_spec, list_games

    return [get_spec(game_id) for game_id in list_games()]


def print_table(rows: list[tuple[str, ...]]) -> None:
    """Left-aligned columns, two spaces apart; the last column is not padded."""
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]) - 1)]
    for row in rows:
        print("  ".join(cell.ljust(w) for cell, w in zip(row, widths)) + "  " + row[-1])
