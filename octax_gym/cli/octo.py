"""`octax-gym asm` and `octax-gym disasm`: Octo source to a ROM (CHIP-8, SUPER-CHIP, XO-CHIP) and back.

    octax-gym asm game.8o                  writes game.ch8 beside it
    octax-gym asm game.8o -o build/game.ch8
    octax-gym disasm game.ch8              Octo source on stdout
    octax-gym disasm game.ch8 -o game.8o

Thin layers over `octax_core.tools.octo` (imported inside the commands: `octax_core` brings JAX). An
Octo error is printed as the assembler words it, with line, column and a caret under the token,
so that a person or a program generator can fix the source from the message alone.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def add_commands(commands: argparse._SubParsersAction) -> None:
    """Adds this module's subcommands to the `octax-gym` parser."""
    asm = commands.add_parser(
        "asm", help="assemble an Octo program (.8o) into a CHIP-8, SUPER-CHIP or XO-CHIP ROM (.ch8)",
        description="Assembles Octo source into the bytes John Earnest's Octo would write, loaded "
                    "at 0x200. On an error, prints its line and column and exits with status 1. "
                    "See docs/octo.md.")
    asm.add_argument("source", type=Path, metavar="FILE.8o", help="the Octo program")
    asm.add_argument("-o", "--output", type=Path, metavar="FILE.ch8",
                     help="the ROM to write (default: FILE.ch8 beside the source)")
    asm.set_defaults(func=_cmd_asm)
    disasm = commands.add_parser(
        "disasm", help="a CHIP-8 ROM (.ch8) back to Octo source (.8o) that reassembles to it",
        description="Writes Octo source (labels, statements for the code reached from 0x200, "
                    "byte rows for data) that `octax-gym asm` turns back into the same bytes. "
                    "See docs/octo.md.")
    disasm.add_argument("rom", type=Path, metavar="FILE.ch8", help="the ROM")
    disasm.add_argument("-o", "--output", type=Path, metavar="FILE.8o",
                        help="the source file to write (default: print to stdout)")
    disasm.set_defaults(func=_cmd_disasm)


def _cmd_asm(args: argparse.Namespace) -> int:
    from octax_core.tools.octo import AssemblyError, assemble

    output = args.output if args.output is not None else args.source.with_suffix(".ch8")
    if output.resolve() == args.source.resolve():
        print(f"octax-gym asm: error: the output {output} would overwrite the source; "
              "name another with -o", file=sys.stderr)
        return 1
    source = args.source.read_text(encoding="utf-8")
    try:
        rom = assemble(source)
    except AssemblyError as exc:
        print(f"octax-gym asm: error: {args.source}: {exc}", file=sys.stderr)
        return 1
    output.write_bytes(rom)
    print(f"wrote {len(rom)} bytes to {output}")
    return 0


def _cmd_disasm(args: argparse.Namespace) -> int:
    from octax_core.tools.octo import disassemble

    source = disassemble(args.rom)
    if args.output is None:
        sys.stdout.write(source)
        return 0
    args.output.write_text(source, encoding="utf-8")
    lines = source.count("\n")
    print(f"wrote {lines} lines of Octo to {args.output}")
    return 0
