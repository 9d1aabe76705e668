"""archive.json: every candidate of a run, accepted or not, with why; written the same, byte for
byte, for the same inputs (no clock, no machine names, rounded scores, fixed key order).

    {"version": 1, "settings": {...}, "games": [{"name", "family", "params", "sha1", "accepted",
     "reasons", "random_score", "reference_score", "split", "source", "rom", "action_keys",
     "registers", ...}, ...]}

`source` and `rom` are file names in the archive's folder (`rom` is null for a program that did
not assemble). `octax_gym.generated.load_archive` reads it back as GameSpecs.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Mapping, Sequence

ARCHIVE = "archive.json"
VERSION = 1
SPLITS = ("train", "test")
REQUIRED = ("name", "family", "params", "sha1", "accepted", "reasons", "random_score", "reference_score", "split",
            "source", "rom", "action_keys", "registers")


def dumps(games: Sequence[Mapping], settings: Mapping) -> str:
    """The archive's text: keys in a fixed order, floats rounded to 4 places, one trailing newline."""
    def clean(value):
        if isinstance(value, float):
            return round(value, 4)
        if isinstance(value, Mapping):
            return {key: clean(item) for key, item in value.items()}
        if isinstance(value, (list, tuple)):
            return [clean(item) for item in value]
        return value
    return json.dumps({"version": VERSION, "settings": clean(dict(settings)), "games": [clean(dict(g)) for g in games]},
                      indent=1) + "\n"


def write(folder, games: Sequence[Mapping], settings: Mapping) -> Path:
    """Writes `folder/archive.json` (the folder is created); returns its path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / ARCHIVE
    path.write_text(dumps(games, settings), encoding="utf-8")
    return path


def read(folder) -> dict:
    """The archive in `folder`, checked: ValueError names a missing file, a bad version or field."""
    path = Path(folder) / ARCHIVE
    if not path.is_file():
        raise ValueError(f"no archive at {path}: `octax-gym generate ... --out {folder}` writes one")
    try:
        archive = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path} is not JSON: {exc}") from None
    if not isinstance(archive, dict) or archive.get("version") != VERSION or not isinstance(archive.get("games"), list):
        raise ValueError(f"{path}: expected an archive of version {VERSION} with a list of games")
    for index, game in enumerate(archive["games"]):
        missing = [key for key in REQUIRED if key not in game]
        if missing:
            raise ValueError(f"{path}: game {index} lacks {', '.join(missing)}")
        if game["split"] not in SPLITS:
            raise ValueError(f"{path}: game {game['name']!r} has split {game['split']!r}; valid: {', '.join(SPLITS)}")
    return archive
