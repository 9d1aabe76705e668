"""Parameters drawn from a seed: variant i of a family under seed s is always the same.

Each variant has its own generator, seeded with (seed, index), so that variant 7 of a run of
64 is variant 7 of a run of 8: a count changes how many, never which.
"""

from __future__ import annotations

import numpy as np

from octax_core.generate.families import Family


def sample_sprite(rng: np.random.Generator, widths: tuple[int, int], heights: tuple[int, int]) -> list[int]:
    """Rows of a random left-aligned shape exactly `width` pixels wide: its first row has the left
    pixel lit, its last row the right one, so the width the game's collisions use is the drawn one."""
    width = int(rng.integers(widths[0], widths[1] + 1))
    height = int(rng.integers(heights[0], heights[1] + 1))
    shift = 8 - width
    rows = [int(rng.integers(1, 2 ** width)) << shift for _ in range(height)]
    rows[0] |= 0x80
    rows[-1] |= 1 << shift
    return rows


def sample_params(family: Family, seed: int, index: int) -> dict:
    """Variant `index` of `family` under `seed`: every range and sprite drawn uniformly."""
    if seed < 0 or index < 0:
        raise ValueError(f"seed and index must be >= 0, got seed={seed}, index={index}")
    rng = np.random.default_rng([seed, index])
    params = {key: int(rng.integers(low, high + 1)) for key, (low, high) in family.ranges.items()}
    for key, (widths, heights) in family.sprites.items():
        params[key] = sample_sprite(rng, widths, heights)
    return params
