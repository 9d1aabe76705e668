"""The `octax-gym` command line (also `python -m octax_gym`).

Each command is one `_cmd_*` function taking the parsed arguments and returning an exit status.
`_build_parser` wires them up: the ROM store's commands are here, the others in one module each
(`cli_games`: list, info; `cli_record`: record; `cli_bench`: bench; `cli_octo`: asm, disasm), each
adding its parsers with `add_commands`. Heavy work (emulation, video, torch) is imported inside the commands.

    octax-gym list [--category C]        every game: Gymnasium id, category, actions, ROM status
    octax-gym info GAME                  one game: actions and keys, spaces, quirks, timers, ROM
    octax-gym record GAME --steps N --out FILE.mp4 [--policy random|noop] [--envs K]
    octax-gym bench [--mode machine|env|gym] [--envs N,...] [--quick] [--no-octax]
    octax-gym trace GAME|ROM [--steps N] [--blind] [--plot FILE.png]   registers: score, lives, game over?
    octax-gym asm FILE.8o [-o FILE.ch8]  assemble Octo source into a ROM (docs/octo.md)
    octax-gym disasm FILE.ch8 [-o FILE.8o]   a ROM back to Octo source that reassembles to it
    octax-gym roms list                  each game's ROM: present?, verified?, where
    octax-gym roms install [--dest DIR]  get the octax==0.1.1 wheel with pip, install its ROMs
    octax-gym roms import PATH [--dest DIR]   the same from a folder, zip or wheel on disk
"""

from __future__ import annotations

import argparse
import sys
import zipfile
from pathlib import Path
from typing import Callable, Optional, Sequence

OCTAX_VERSION = "0.1.1"  # the published wheel whose ROMs the games were written against


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Runs the command line; returns the exit status (0 ok, 1 failed, 2 bad usage)."""
    parser = _build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "func"):
        parser.print_help()
        return 2
    from octax_core import romstore  # after parsing: it imports JAX

    try:
        return args.func(args)
    except (romstore.RomNotFoundError, romstore.RomHashError, romstore.RomInstallError,
            OSError, ValueError, ImportError, zipfile.BadZipFile) as exc:
        print(f"octax-gym: error: {exc}", file=sys.stderr)
        return 1


def _build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="octax-gym", description="CHIP-8 games as reinforcement-learning environments.")
    commands = parser.add_subparsers(title="commands", metavar="COMMAND")
    # One module per command group; each imports only argparse at module level.
    from octax_gym import cli_bench, cli_games, cli_octo, cli_record, cli_trace

    cli_games.add_commands(commands)
    _add_roms(commands)
    cli_record.add_commands(commands)
    cli_bench.add_commands(commands)
    cli_octo.add_commands(commands)
    cli_trace.add_commands(commands)
    return parser


def _add_roms(commands: argparse._SubParsersAction) -> None:
    roms = commands.add_parser("roms", help="list, install or import the games' ROMs",
                               description="The ROM store; see docs/roms.md.")
    roms.set_defaults(func=help_of(roms))
    sub = roms.add_subparsers(title="roms commands", metavar="ACTION")
    sub.add_parser("list", help="each game's ROM: present, verified, path").set_defaults(func=_cmd_roms_list)
    install = sub.add_parser("install", help=f"download the octax=={OCTAX_VERSION} wheel with pip and "
                                             "install the ROMs whose hashes match")
    install.add_argument("--dest", type=Path, help="target folder (default: the user data folder)")
    install.set_defaults(func=_cmd_roms_install)
    imp = sub.add_parser("import", help="install matching ROMs from a folder, zip or wheel on disk")
    imp.add_argument("path", type=Path, help="folder (searched recursively), .zip or .whl")
    imp.add_argument("--dest", type=Path, help="target folder (default: the user data folder)")
    imp.set_defaults(func=_cmd_roms_import)


def help_of(parser: argparse.ArgumentParser) -> Callable[[argparse.Namespace], int]:
    def show(_args: argparse.Namespace) -> int:
        parser.print_help()
        return 2
    return show


def game_specs() -> list:
    """Every registered `GameSpec` (imports the registry, hence JAX)."""
    from octax_core.games import get_spec, list_games

    return [get_spec(game_id) for game_id in list_games()]


def lookup_spec(name: str):
    """The spec for a game id or Gymnasium id, exact first, then ignoring case; None if unknown."""
    from octax_core.games import get_spec, list_games
    from octax_gym.registration import env_id

    names = {game: game for game in list_games()} | {env_id(game): game for game in list_games()}
    game = names.get(name) or {key.lower(): value for key, value in names.items()}.get(name.lower())
    return None if game is None else get_spec(game)


def _cmd_roms_list(args: argparse.Namespace) -> int:
    from octax_core import romstore

    rows = romstore.rom_status(game_specs())
    if not rows:
        print("no games registered")
        return 0
    table = [("game", "rom file", "present", "verified", "path")]
    for row in rows:
        verified = "yes" if row.verified else ("-" if row.path is None else "NO: sha1 " + row.actual_sha1)
        table.append((row.game_id, row.rom_file, "yes" if row.path else "missing", verified,
                      str(row.path) if row.path else "-"))
    print_table(table)
    n_ok = sum(row.verified for row in rows)
    print(f"\n{n_ok}/{len(rows)} ROMs present and verified. Searched: "
          + ", ".join(str(d) for d in romstore.search_dirs()))
    if n_ok < len(rows):
        print(f"To fix: {romstore.FIX_HINT}.")
    return 0


def _cmd_roms_install(args: argparse.Namespace) -> int:
    from octax_core import romstore

    specs = game_specs()
    print(f"downloading octax=={OCTAX_VERSION} with pip ...")
    results = romstore.install_from_pypi(specs, args.dest, OCTAX_VERSION)
    return _report_import(results, specs, args.dest)


def _cmd_roms_import(args: argparse.Namespace) -> int:
    from octax_core import romstore

    specs = game_specs()
    return _report_import(romstore.import_roms(args.path, specs, args.dest), specs, args.dest)


def _report_import(results: list, specs: list, dest: Optional[Path]) -> int:
    """Prints what was installed and which games still lack a ROM; 1 if nothing matched."""
    from octax_core import romstore

    if not specs:
        print("no games registered: nothing to install")
        return 0
    for r in results:
        print(f"{r.action:9}  {r.rom_file}  ({', '.join(r.game_ids)})")
    dest = (dest if dest is not None else romstore.user_rom_dir()).expanduser().resolve()
    covered = {game_id for r in results for game_id in r.game_ids}
    missing = [spec.id for spec in specs if spec.id not in covered]
    print(f"{len(results)} ROM files in {dest}"
          + (f"; no matching ROM for: {', '.join(missing)}" if missing else "; every game has its ROM"))
    if results and dest not in romstore.search_dirs():
        print(f"note: {dest} is not searched; add it to OCTAX_ROM_DIR to use these ROMs")
    if not results:
        print("octax-gym: error: no file there has the SHA-1 of any game's ROM", file=sys.stderr)
        return 1
    return 0


def print_table(rows: list[tuple[str, ...]]) -> None:
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]) - 1)]
    for row in rows:
        print("  ".join(cell.ljust(w) for cell, w in zip(row, widths)) + "  " + row[-1])


if __name__ == "__main__":
    sys.exit(main())
