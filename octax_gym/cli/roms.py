"""`octax-gym roms list | install | import`: the ROM store (`octax_core.env.romstore`) on the command line.

    octax-gym roms list                  each game's ROM: present?, verified?, where
    octax-gym roms install [--dest DIR]  get the octax==0.1.1 wheel with pip, install its ROMs
    octax-gym roms import PATH [--dest DIR]   the same from a folder, zip or wheel on disk
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Optional

from octax_gym.cli.common import game_specs, help_of, print_table

OCTAX_VERSION = "0.1.1"  # the published wheel whose ROMs the games were written against


def add_commands(commands: argparse._SubParsersAction) -> None:
    """Adds `roms` and its actions to the `octax-gym` parser."""
    roms = commands.add_parser("roms", help="list, install or import the games' ROMs",
                               description="The ROM store; see docs/roms.md.")
    roms.set_defaults(func=help_of(roms))
    sub = roms.add_subparsers(title="roms commands", metavar="ACTION")
    sub.add_parser("list", help="each game's ROM: present, verified, path").set_defaults(func=_cmd_roms_list)
    install = sub.add_parser("install", help=f"download the octax=={OCTAX_VERSION} wheel with pip and "
                                             "install the ROMs whose hashes match")
    install.add_argument("--dest", type=Path, help="target folder (default: the user data folder)")
    install.add_argument("--if-missing", action="store_true",
                         help="download only if some game has no verified ROM in the folders searched "
                              "(what `make demo` and `make test` run: no network when all are there)")
    install.set_defaults(func=_cmd_roms_install)
    imp = sub.add_parser("import", help="install matching ROMs from a folder, zip or wheel on disk")
    imp.add_argument("path", type=Path, help="folder (searched recursively), .zip or .whl")
    imp.add_argument("--dest", type=Path, help="target folder (default: the user data folder)")
    imp.set_defaults(func=_cmd_roms_import)


def _cmd_roms_list(args: argparse.Namespace) -> int:
    from octax_core.env import romstore

    rows = romstore.rom_status(game_specs(two_player_only=True))
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
    from octax_core.env import romstore

    specs = game_specs(two_player_only=True)
    if args.if_missing:
        missing = [row.game_id for row in romstore.rom_status(specs) if not row.verified]
        if not missing:
            print(f"every game ({len(specs)}) has its verified ROM already; nothing to download. Searched: "
                  + ", ".join(str(d) for d in romstore.search_dirs()))
            return 0
        print(f"{len(missing)} game(s) without a verified ROM: {', '.join(missing)}")
    print(f"downloading octax=={OCTAX_VERSION} with pip ...")
    results = romstore.install_from_pypi(specs, args.dest, OCTAX_VERSION)
    return _report_import(results, specs, args.dest)


def _cmd_roms_import(args: argparse.Namespace) -> int:
    from octax_core.env import romstore

    specs = game_specs(two_player_only=True)
    return _report_import(romstore.import_roms(args.path, specs, args.dest), specs, args.dest)


def _report_import(results: list, specs: list, dest: Optional[Path]) -> int:
    """Prints what was installed and which games still lack a ROM; 1 if nothing matched.

    A game counts as missing only if no folder searched has its ROM either: our own games (built
    from roms/*.8o) are never in the octax wheel, and are not missing when roms/ has them.
    """
    from octax_core.env import romstore

    if not specs:
        print("no games registered: nothing to install")
        return 0
    for r in results:
        print(f"{r.action:9}  {r.rom_file}  ({', '.join(r.game_ids)})")
    dest = (dest if dest is not None else romstore.user_rom_dir()).expanduser().resolve()
    covered = {game_id for r in results for game_id in r.game_ids}
    covered |= {row.game_id for row in romstore.rom_status(specs) if row.verified}
    missing = [spec.id for spec in specs if spec.id not in covered]
    print(f"{len(results)} ROM files in {dest}"
          + (f"; no matching ROM for: {', '.join(missing)}" if missing else "; every game has its ROM"))
    if results and dest not in romstore.search_dirs():
        print(f"note: {dest} is not searched; add it to OCTAX_ROM_DIR to use these ROMs")
    if not results:
        print("octax-gym: error: no file there has the SHA-1 of any game's ROM", file=sys.stderr)
        return 1
    return 0
