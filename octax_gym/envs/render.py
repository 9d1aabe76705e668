"""Screens to RGB frames: palettes, the OpenCV nearest-neighbour upscale, and frame grids.

Host-side numpy only (no JAX, no pygame): a frame is made when someone asks for one, from the
packed screen words the env hands over, so rendering never touches the jitted step.
"""

from __future__ import annotations

from typing import Sequence, Union

import cv2
import numpy as np

from octax_core.validate import check_int
from octax_gym.envs.choices import check_choice

RGB = tuple[int, int, int]

# (off, on) colours, then XO-CHIP's two more: plane 2 alone, and both planes. "octo" is the Octo
# IDE's default set (background, fill, fill 2, blend); the rest are phosphor looks.
PALETTES: dict[str, tuple[RGB, ...]] = {
    "white": ((0, 0, 0), (255, 255, 255), (170, 170, 170), (85, 85, 85)),
    "octo": ((153, 102, 0), (255, 204, 0), (255, 102, 0), (102, 34, 0)),
    "green": ((0, 24, 0), (51, 255, 102), (20, 150, 60), (150, 255, 180)),
    "amber": ((24, 12, 0), (255, 176, 0), (170, 90, 0), (255, 230, 150)),
    "blue": ((0, 0, 48), (120, 200, 255), (40, 90, 200), (220, 240, 255)),
}
DEFAULT_PALETTE = "white"
DEFAULT_RENDER_SCALE = 8
MAX_RENDER_SCALE = 64

PaletteArg = Union[str, Sequence[Sequence[int]]]


def resolve_palette(palette: PaletteArg) -> np.ndarray:
    """A palette name, an (off, on) pair or an (off, plane 1, plane 2, both) set of RGB triples
    -> uint8 array (4, 3), indexed by a pixel's value (`octax_core.emulator.state.screen_values`).

    A pair serves XO-CHIP too: plane 2 alone is drawn halfway between off and on, both planes a
    quarter of the way (CHIP-8 and SUPER-CHIP pixels only ever use the first two).

    Raises:
        UnknownOptionError: an unknown name; the message lists the valid ones.
        ValueError: a malformed set.
    """
    if isinstance(palette, str):
        check_choice("palette", palette, PALETTES, "or an (off, on) pair of RGB triples")
        return np.array(PALETTES[palette], np.uint8)
    try:
        colours = np.array(palette)
    except (TypeError, ValueError):
        colours = np.array(None)
    if (colours.shape not in ((2, 3), (4, 3)) or not np.issubdtype(colours.dtype, np.integer)
            or colours.min() < 0 or colours.max() > 255):
        raise ValueError(f"palette must be a name ({', '.join(PALETTES)}) or an (off, on) pair of "
                         f"RGB triples (or 4: off, plane 1, plane 2, both) with values 0..255, got {palette!r}")
    if len(colours) == 2:
        off, on = colours.astype(np.int32)
        colours = np.stack([off, on, (off + on) // 2, (3 * off + on) // 4])
    return colours.astype(np.uint8)


def check_render_scale(scale) -> int:
    return check_int("render_scale", scale, 1, MAX_RENDER_SCALE)


def to_rgb(pixels: np.ndarray, scale: int, palette: np.ndarray) -> np.ndarray:
    """(H, W) pixel values (bool, or 0..3 on XO-CHIP) -> (H*scale, W*scale, 3) uint8 in the
    palette's colours, upscaled nearest-neighbour by OpenCV."""
    small = palette[pixels.astype(np.intp)]
    if scale == 1:
        return np.ascontiguousarray(small)
    height, width = pixels.shape
    return cv2.resize(small, (width * scale, height * scale), interpolation=cv2.INTER_NEAREST)


def tile(frames: Sequence[np.ndarray], columns: int | None = None, gap: int = 2) -> np.ndarray:
    """Frames of one shape -> one grid image (row-major, `gap` grey pixels between cells).

    The grid's sides are rounded up to even numbers, which H.264 with 4:2:0 chroma needs.
    """
    if not len(frames):
        raise ValueError("tile needs at least one frame")
    count = len(frames)
    columns = columns or int(np.ceil(np.sqrt(count)))
    rows = int(np.ceil(count / columns))
    h, w, c = frames[0].shape
    height, width = rows * h + (rows - 1) * gap, columns * w + (columns - 1) * gap
    grid = np.full((height + height % 2, width + width % 2, c), 64, np.uint8)
    for index, frame in enumerate(frames):
        r, col = divmod(index, columns)
        grid[r * (h + gap): r * (h + gap) + h, col * (w + gap): col * (w + gap) + w] = frame
    return grid
