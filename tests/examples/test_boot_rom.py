"""examples/boot_rom.py runs from a clone with nothing beside it: its default ROM is our own Dodge."""

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def test_boot_rom_example_prints_the_screen_and_a_matching_batch():
    result = subprocess.run([sys.executable, "examples/boot_rom.py"], capture_output=True, text=True,
                            timeout=300, cwd=REPO, check=False)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    screen = lines[:32]
    assert all(len(row) == 64 and set(row) <= {"#", "."} for row in screen)
    assert sum(row.count("#") for row in screen) == 60  # Dodge's start screen
    assert lines[32].startswith("batch of 4: screens (4, 32, 64)") and lines[32].endswith("True")
