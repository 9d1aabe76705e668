"""examples/boot_superchip.py runs from a clone with nothing beside it: its default program is inline."""

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def test_boot_superchip_example_prints_the_big_digit_scrolled_down():
    result = subprocess.run([sys.executable, "examples/boot_superchip.py"], capture_output=True, text=True,
                            timeout=300, cwd=REPO, check=False)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    screen = lines[:64]
    assert all(len(row) == 128 and set(row) <= {"#", "."} for row in screen)
    # the big 8 (8x10), drawn at (48, 16) and scrolled down 4 rows
    digit = [row[48:56] for row in screen[20:30]]
    assert digit == ["########", "########", "##....##", "##....##", "########", "########", "##....##", "##....##",
                     "########", "########"]
    assert sum(row.count("#") for row in screen) == 64
    assert lines[64] == "schip: screen (64, 128), hires True, exited False, lit pixels 64"
