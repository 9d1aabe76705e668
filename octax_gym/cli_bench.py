"""`octax-gym bench`: (being written)."""

from __future__ import annotations

import argparse


def add_commands(commands: argparse._SubParsersAction) -> None:
    """Adds this module's subcommands to the `octax-gym` parser."""
