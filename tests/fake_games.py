"""Fake games for the ROM store tests: real `GameSpec`s over small byte strings, and specs read
from a `SHA1SUMS` manifest (so the real ROMs can be checked while the registry is still filling)."""

from __future__ import annotations

import hashlib
from pathlib import Path

from octax_core.env.games.spec import GameSpec


def sha1(data: bytes) -> str:
    return hashlib.sha1(data).hexdigest()


def make_spec(game_id: str, rom_file: str, data: bytes) -> GameSpec:
    """A playable-looking spec whose ROM is `data`, stored as `rom_file`."""
    return GameSpec(
        id=game_id, title=game_id, rom_file=rom_file, rom_sha1=sha1(data), action_keys=(1,),
        score_fn=lambda state: 0, terminated_fn=lambda state: False, category="reaction",
        description=f"fake game {game_id}",
    )


def read_sha1sums(path: Path) -> dict[str, str]:
    """`sha1sum` output -> {file name: sha1}; names may hold spaces."""
    entries = {}
    for line in path.read_text().splitlines():
        if line.strip():
            digest, name = line.split(None, 1)
            entries[name.lstrip("*").strip()] = digest.lower()
    return entries


def specs_from_sha1sums(path: Path) -> list[GameSpec]:
    """One fake spec per `.ch8` in a `SHA1SUMS` manifest, id = file stem."""
    return [
        GameSpec(id=Path(name).stem, title=name, rom_file=name, rom_sha1=digest, action_keys=(1,),
                 score_fn=lambda state: 0, terminated_fn=lambda state: False, category="reaction",
                 description="from SHA1SUMS")
        for name, digest in sorted(read_sha1sums(path).items()) if name.endswith(".ch8")
    ]
