"""Where the tests find third-party data, which is never committed.

* The octax suite's game ROMs: in `OCTAX_ROM_DIR` (../shared/roms/octax on our machines and in
  CI), else in the user data folder, where `octax-gym roms install` puts them from PyPI (`make
  test` runs it when they are missing). `octax_rom_folder()` finds them.
* Everything else in ../shared (the GPL Timendus test-suite ROMs, the Octo sources of the octax
  games, the SHA1SUMS manifests): no package index serves these files (none of the CHIP-8
  packages we looked at on PyPI ships them), so tests that read them are marked `shared`. Without ../shared they are
  skipped with a reason; with OCTAX_REQUIRE_SHARED=1 (set by .ci/run) they fail instead, so that
  CI, which has ../shared, can never go green by skipping them.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Optional

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
TEST_SUITE_DIR = SHARED / "roms" / "test-suite"
REQUIRE_SHARED = os.environ.get("OCTAX_REQUIRE_SHARED") == "1"


def missing_shared(path: Path) -> Optional[str]:
    """Why a test that needs `path` (under ../shared) cannot run, or None when it can."""
    if path.exists():
        return None
    return (f"needs {path}: third-party data that is never committed and that no package index serves "
            "(the test-suite ROMs, Octo sources, SHA1SUMS manifests); put ../shared beside the repository")


def octax_rom_folder() -> Optional[Path]:
    """The first folder holding every third-party game's ROM, verified: an `OCTAX_ROM_DIR` entry,
    then the user data folder. None when there is none."""
    from octax_core.env import romstore
    from octax_core.env.games import get_spec, list_games

    third_party = [get_spec(g) for g in list_games() if not (romstore.PROJECT_ROM_DIR / get_spec(g).rom_file).is_file()]
    folders = [Path(e).expanduser().resolve() for e in os.environ.get("OCTAX_ROM_DIR", "").split(os.pathsep) if e]
    for folder in [*folders, romstore.user_rom_dir()]:
        if folder.is_dir() and all(_verified(folder / spec.rom_file, spec.rom_sha1) for spec in third_party):
            return folder
    return None


def _verified(path: Path, sha1: str) -> bool:
    import hashlib

    return path.is_file() and hashlib.sha1(path.read_bytes()).hexdigest() == sha1.lower()
