"""What every archive game takes from the archive itself: its ROM, platform, quirks, speed, colours.

programs.json gives each program the options the Octo IDE ran it with: the platform, the tickrate
(instructions per 60 Hz frame), the quirk flags (`quirks_from_octo`) and the colours (background,
fill and, for XO-CHIP, fill 2 and blend). `archive_spec` reads them, so a game module states only
what the archive does not: its keys, start-up, score, lives and end.
"""

from __future__ import annotations

import functools
import json
from typing import Any, Optional

from octax_core.emulator.quirks import quirks_from_octo
from octax_core.env.games.spec import GameSpec
from octax_core.env.romstore import ARCHIVE_ROM_DIR


@functools.lru_cache(maxsize=None)
def programs() -> dict[str, dict[str, Any]]:
    """The archive's programs.json (shipped beside the ROMs): name -> title, authors, platform, options."""
    return json.loads((ARCHIVE_ROM_DIR / "programs.json").read_text(encoding="utf-8"))


def program(name: str) -> dict[str, Any]:
    """One program's programs.json entry.

    Raises:
        KeyError: no such program; the message lists the valid names.
    """
    try:
        return programs()[name]
    except KeyError:
        raise KeyError(f"no program {name!r} in the archive; valid: {', '.join(sorted(programs()))}") from None


# The CSS colour names programs.json uses besides '#RRGGBB' (values from the CSS Color Module).
CSS_COLOURS = {
    "black": "#000000", "white": "#FFFFFF", "gray": "#808080", "lightgray": "#D3D3D3", "red": "#FF0000",
    "navy": "#000080", "lightcyan": "#E0FFFF", "lavender": "#E6E6FA", "aquamarine": "#7FFFD4",
    "hotpink": "#FF69B4", "deeppink": "#FF1493", "powderblue": "#B0E0E6",
}


def _rgb(colour: str) -> tuple[int, int, int]:
    """'#RRGGBB', '#RGB' or a CSS colour name -> (r, g, b).

    Raises:
        ValueError: a colour neither form names.
    """
    code = CSS_COLOURS.get(colour.lower(), colour)
    digits = code.lstrip("#")
    if len(digits) == 3:
        digits = "".join(d * 2 for d in digits)
    if not code.startswith("#") or len(digits) != 6:
        raise ValueError(f"colour {colour!r}: not '#RRGGBB', '#RGB' or one of {', '.join(sorted(CSS_COLOURS))}")
    value = int(digits, 16)
    return (value >> 16) & 0xFF, (value >> 8) & 0xFF, value & 0xFF


def archive_palette(name: str) -> Optional[tuple[tuple[int, int, int], ...]]:
    """The program's own colours: (background, fill), and for XO-CHIP (background, fill, fill 2,
    blend), the order `GameSpec.palette` takes; None where programs.json names none."""
    entry = program(name)
    options = entry["options"]
    keys = ("backgroundColor", "fillColor") + (("fillColor2", "blendColor") if entry["platform"] == "xochip" else ())
    if not all(options.get(key) for key in keys):
        return None
    return tuple(_rgb(options[key]) for key in keys)


def archive_spec(name: str, *, id: str, rom_sha1: str, title: Optional[str] = None, **fields: Any) -> GameSpec:
    """The `GameSpec` of archive program `name` (the ROM's file name without .ch8).

    Platform, quirks, instructions per frame (the tickrate) and palette come from programs.json
    unless `fields` gives them; the title is the archive's unless `title` is given; `rom_sha1` is
    stated by the game module (the ROM store refuses any other bytes); `fields` give the rest
    (action_keys, score_fn, terminated_fn, startup, ...).
    """
    entry = program(name)
    options = entry["options"]
    defaults = dict(
        platform=entry["platform"],
        quirks=quirks_from_octo(options),
        instructions_per_frame=int(options["tickrate"]),
        palette=archive_palette(name),
    )
    return GameSpec(id=id, title=title or entry["title"], rom_file=f"archive/{name}.ch8", rom_sha1=rom_sha1,
                    **{**defaults, **fields})


def authors(name: str) -> tuple[str, ...]:
    """The program's authors as the archive credits them."""
    return tuple(program(name)["authors"])
