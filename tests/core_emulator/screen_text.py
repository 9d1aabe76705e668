"""Read glyphs and marks off a (32, 64) bool CHIP-8 screen, independently of the core.

Everything here is transcribed from the Timendus test-suite sources (`*.8o` in
`shared/roms/test-suite/`), so tests can state what the ROM should have drawn without
asking the emulator under test.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

HEIGHT, WIDTH = 32, 64

SHARED = Path(__file__).resolve().parents[2].parent / "shared"
SUITE = SHARED / "roms" / "test-suite"

# 3-corax+.8o `image-ok` / `image-no`: 4 rows, drawn with `sprite x2 y 4`.
CORAX_OK = (0x00, 0xA0, 0xC0, 0x80)
CORAX_NO = (0x00, 0xA0, 0x40, 0xA0)

# 4-flags.8o, 5-quirks.8o, 6-keypad.8o `flag-ok` / `flag-err`: 3 rows, drawn with `sprite x y 3`.
FLAG_OK = (0xA0, 0xC0, 0x80)
FLAG_ERR = (0xA0, 0x40, 0xA0)

# 5-quirks.8o's result lines: (label, Quirks field, y); label at (1, y), result at (42, y), mark at (59, y + 1).
QUIRK_ROWS = [
    ("VF RESET", "vf_reset", 1), ("MEMORY", "memory_increment", 6), ("DISP.WAIT", "display_wait", 11),
    ("CLIPPING", "clipping", 16), ("SHIFTING", "shift_uses_vy", 21), ("JUMPING", "jump_uses_vx", 26),
]

# The 3x4 character set shared by 4-flags, 5-quirks and 6-keypad (`im0` .. `imPeriod`), in
# the order of their `:stringmode str "$0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ -."`.
GLYPHS: dict[str, tuple[int, int, int, int]] = {
    "0": (0xE0, 0xA0, 0xA0, 0xE0),
    "1": (0xC0, 0x40, 0x40, 0xE0),
    "2": (0xE0, 0x20, 0xC0, 0xE0),
    "3": (0xE0, 0x60, 0x20, 0xE0),
    "4": (0xA0, 0xE0, 0x20, 0x20),
    "5": (0xE0, 0xC0, 0x20, 0xC0),
    "6": (0xE0, 0x80, 0xE0, 0xE0),
    "7": (0xE0, 0x20, 0x20, 0x20),
    "8": (0xE0, 0xE0, 0xA0, 0xE0),
    "9": (0xE0, 0xE0, 0x20, 0xE0),
    "A": (0x40, 0xA0, 0xE0, 0xA0),
    "B": (0xC0, 0xE0, 0xA0, 0xE0),
    "C": (0xE0, 0x80, 0x80, 0xE0),
    "D": (0xC0, 0xA0, 0xA0, 0xC0),
    "E": (0xE0, 0xC0, 0x80, 0xE0),
    "F": (0xE0, 0x80, 0xC0, 0x80),
    "G": (0x60, 0x80, 0xA0, 0x60),
    "H": (0xA0, 0xE0, 0xA0, 0xA0),
    "I": (0xE0, 0x40, 0x40, 0xE0),
    "J": (0x60, 0x20, 0x20, 0xC0),
    "K": (0xA0, 0xC0, 0xA0, 0xA0),
    "L": (0x80, 0x80, 0x80, 0xE0),
    "M": (0xE0, 0xE0, 0xA0, 0xA0),
    "N": (0xC0, 0xA0, 0xA0, 0xA0),
    "O": (0xE0, 0xA0, 0xA0, 0xE0),
    "P": (0xC0, 0xA0, 0xC0, 0x80),
    "Q": (0x40, 0xA0, 0xE0, 0x60),
    "R": (0xC0, 0xA0, 0xC0, 0xA0),
    "S": (0x60, 0xC0, 0x20, 0xC0),
    "T": (0xE0, 0x40, 0x40, 0x40),
    "U": (0xA0, 0xA0, 0xA0, 0x60),
    "V": (0xA0, 0xA0, 0xA0, 0x40),
    "W": (0xA0, 0xA0, 0xE0, 0xE0),
    "X": (0xA0, 0x40, 0xA0, 0xA0),
    "Y": (0xA0, 0xA0, 0x40, 0x40),
    "Z": (0xE0, 0x60, 0x80, 0xE0),
    " ": (0x00, 0x00, 0x00, 0x00),
    "-": (0x00, 0xE0, 0x00, 0x00),
    ".": (0x00, 0x00, 0x00, 0x40),
}
GLYPH_TABLE_BYTES = bytes(b for ch in "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ -." for b in GLYPHS[ch])


def sprite_bits(rows, width: int = 8) -> np.ndarray:
    """Sprite bytes as a (len(rows), width) bool array, most significant bit on the left."""
    rows = np.asarray(list(rows), dtype=np.uint8)
    return np.unpackbits(rows[:, None], axis=1)[:, :width].astype(bool)


def blank() -> np.ndarray:
    return np.zeros((HEIGHT, WIDTH), dtype=bool)


def blit(screen: np.ndarray, rows, x: int, y: int, *, clip: bool = True) -> bool:
    """XOR-draw sprite bytes at (x mod 64, y mod 32) in place, as DXYN does. Returns the collision flag."""
    x, y = x % WIDTH, y % HEIGHT
    erased = False
    for dy, row in enumerate(sprite_bits(rows)):
        for dx, lit in enumerate(row):
            px, py = x + dx, y + dy
            if clip and (px >= WIDTH or py >= HEIGHT):
                continue
            px, py = px % WIDTH, py % HEIGHT
            if lit:
                erased |= bool(screen[py, px])
                screen[py, px] ^= True
    return erased


def cell(screen: np.ndarray, x: int, y: int, height: int, width: int = 3) -> np.ndarray:
    """The (height, width) block of `screen` at (x, y); must lie fully on screen."""
    assert 0 <= x and x + width <= WIDTH and 0 <= y and y + height <= HEIGHT, (x, y, width, height)
    return screen[y : y + height, x : x + width]


def matches(screen: np.ndarray, rows, x: int, y: int, width: int = 3) -> bool:
    """Whether the block at (x, y) holds exactly the sprite `rows` (its leftmost `width` columns)."""
    return bool(np.array_equal(cell(screen, x, y, len(rows), width), sprite_bits(rows, width)))


def mark_at(screen: np.ndarray, x: int, y: int, ok, bad, width: int = 3) -> str:
    """'ok', 'bad' or 'missing' for the result mark expected at (x, y)."""
    if matches(screen, ok, x, y, width):
        return "ok"
    if matches(screen, bad, x, y, width):
        return "bad"
    return "missing"


def find_all(screen: np.ndarray, rows, width: int = 3) -> list[tuple[int, int]]:
    """Every (x, y) where the block equals the sprite exactly (a coarse search; may hit inside glyphs)."""
    pattern = sprite_bits(rows, width)
    h = len(rows)
    return [
        (x, y)
        for y in range(HEIGHT - h + 1)
        for x in range(WIDTH - width + 1)
        if np.array_equal(screen[y : y + h, x : x + width], pattern)
    ]


_BY_BITS = {sprite_bits(rows, 3).tobytes(): ch for ch, rows in reversed(GLYPHS.items())}  # '0' over 'O'


def read_char(screen: np.ndarray, x: int, y: int) -> str:
    """The glyph in the 3x4 block at (x, y), or '?' if it is none of the Timendus characters.

    '0' and 'O' are the same picture; this returns '0'. Use `text_at` to check text.
    """
    return _BY_BITS.get(cell(screen, x, y, 4).tobytes(), "?")


def read_text(screen: np.ndarray, x: int, y: int, length: int) -> str:
    """`length` characters drawn from (x, y) with a 4-pixel advance, as the ROMs' `drawText` does,
    with trailing blanks stripped."""
    return "".join(read_char(screen, x + 4 * i, y) for i in range(length)).rstrip(" ")


def text_at(screen: np.ndarray, x: int, y: int, text: str) -> bool:
    """Whether `text` is drawn from (x, y) as `drawText` does (a space must be blank).

    Compares pixels, so the look-alikes '0' and 'O' both match either glyph.
    """
    return all(matches(screen, GLYPHS[ch], x + 4 * i, y) for i, ch in enumerate(text))


def to_text(screen: np.ndarray) -> str:
    """The screen as '#'/'.' lines, for failure messages."""
    return "\n".join("".join("#" if p else "." for p in row) for row in np.asarray(screen))


def octo_bytes(source: str, label: str) -> bytes:
    """The data bytes that follow `: label` in an Octo source, up to the next label or directive."""
    lines = source.splitlines()
    start = next(i for i, line in enumerate(lines) if line.split("#")[0].split() == [":", label])
    out = []
    for line in lines[start + 1 :]:
        words = line.split("#")[0].split()
        if words and (words[0].startswith(":") or not re.fullmatch(r"0x[0-9a-fA-F]+|0b[01]+|\d+", words[0])):
            break
        out += [int(w, 0) for w in words]
    return bytes(out)
