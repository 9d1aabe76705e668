"""A variant's Octo source: a family's template with its parameters filled in.

Every parameter is checked against the family's ranges first, so that a hand-written variant
(params edited in an archive, say) that the template was never meant for is refused by name
rather than assembled into a game whose positions overflow the screen.
"""

from __future__ import annotations

import string
from typing import Mapping

from octax_core.generate.families import Family


def sprite_width(rows) -> int:
    """Columns from the sprite's left edge to its rightmost lit pixel (rows are left-aligned)."""
    lowest = min((row & -row).bit_length() for row in rows if row)
    return 9 - lowest


def check_params(family: Family, params: Mapping) -> None:
    """Raises ValueError naming a missing, unknown or out-of-range parameter and the valid ones."""
    expected = set(family.ranges) | set(family.sprites)
    if set(params) != expected:
        missing, unknown = sorted(expected - set(params)), sorted(set(params) - expected)
        raise ValueError(f"{family.name}: params must be exactly {', '.join(sorted(expected))}; "
                         f"missing: {', '.join(missing) or '-'}, unknown: {', '.join(unknown) or '-'}")
    for key, (low, high) in family.ranges.items():
        if not isinstance(params[key], int) or not low <= params[key] <= high:
            raise ValueError(f"{family.name}: {key} must be an integer in {low}..{high}, got {params[key]!r}")
    for key, ((w_low, w_high), (h_low, h_high)) in family.sprites.items():
        rows = params[key]
        ok = (isinstance(rows, (list, tuple)) and h_low <= len(rows) <= h_high
              and all(isinstance(r, int) and 0 <= r <= 255 for r in rows) and any(rows)
              and any(r & 0x80 for r in rows) and w_low <= sprite_width(rows) <= w_high)
        if not ok:
            raise ValueError(f"{family.name}: {key} must be {h_low}..{h_high} rows of bytes, left-aligned "
                             f"(a row with its left pixel lit), {w_low}..{w_high} pixels wide, got {rows!r}")


def render(family: Family, params: Mapping) -> str:
    """The variant's Octo source (see `check_params` for what is refused)."""
    check_params(family, params)
    fields = {key: value for key, value in params.items() if key not in family.sprites}
    sizes = {}
    for key in family.sprites:
        rows = params[key]
        fields[key] = " ".join(f"0b{row:08b}" for row in rows)
        sizes[f"{key}_h"], sizes[f"{key}_w"] = len(rows), sprite_width(rows)
    fields.update(sizes)
    fields.update(family.derive({**params, **sizes}))
    return string.Template(family.template).substitute(fields)
