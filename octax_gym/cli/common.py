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
