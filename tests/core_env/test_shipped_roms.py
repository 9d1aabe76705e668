"""The ROMs that ship inside the package (octax_core/env/roms/): our own games and the Chip8
Community Archive's CC0 programs. A wheel carries them, so a `pip install` has them without the
ROM store's download; the archive's files are unchanged and credited."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from octax_core.env.romstore import ARCHIVE_ROM_DIR, PROJECT_ROM_DIR

REPO = Path(__file__).resolve().parents[2]


def archive_programs() -> dict:
    return json.loads((ARCHIVE_ROM_DIR / "programs.json").read_text())


def test_every_archive_program_is_there_unchanged():
    programs = archive_programs()
    sums = dict(reversed(line.split()) for line in (ARCHIVE_ROM_DIR / "SHA1SUMS").read_text().splitlines() if line)
    assert len(programs) == 101 and sorted(sums) == sorted(f"{name}.ch8" for name in programs)
    for file, sha1 in sums.items():
        assert hashlib.sha1((ARCHIVE_ROM_DIR / file).read_bytes()).hexdigest() == sha1, file
    assert sorted(p.name for p in ARCHIVE_ROM_DIR.glob("*.ch8")) == sorted(sums)
    platforms = sorted(entry["platform"] for entry in programs.values())
    assert (platforms.count("chip8"), platforms.count("schip"), platforms.count("xochip")) == (48, 25, 28)


def test_the_licence_note_says_cc0_and_credits_every_program():
    note = (ARCHIVE_ROM_DIR / "LICENSE.md").read_text()
    assert "Creative Commons Zero" in note and "0a41cc23ad5c" in note
    for name, entry in archive_programs().items():
        row = next(line for line in note.splitlines() if line.startswith(f"| {name} |"))
        assert all(author in row for author in entry["authors"]) and entry["platform"] in row


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """A wheel built from this checkout (setuptools, no network)."""
    folder = tmp_path_factory.mktemp("dist")
    result = subprocess.run([sys.executable, "-m", "pip", "wheel", str(REPO), "--no-deps", "--no-build-isolation",
                             "-q", "-w", str(folder)], capture_output=True, text=True, timeout=300, check=False)
    assert result.returncode == 0, result.stderr
    (built,) = folder.glob("octax_gym-*.whl")
    return built


def test_a_wheel_ships_our_roms_and_the_archive(wheel):
    """The fix for wheels that lacked Dodge and Flak."""
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
        for name in ("dodge.ch8", "flak.ch8"):
            assert archive.read(f"octax_core/env/roms/{name}") == (PROJECT_ROM_DIR / name).read_bytes()
        shipped = {Path(n).name for n in names if n.startswith("octax_core/env/roms/archive/")}
    assert shipped == {p.name for p in ARCHIVE_ROM_DIR.iterdir()}


def test_archive_games_play_from_the_wheel_alone(wheel, tmp_path):
    """The wheel's own files, not this checkout's, with an empty HOME and no OCTAX_ROM_DIR: archive
    games build from the ROMs inside it. (`python -S` skips site-packages' .pth files, so the
    checkout's editable install is not imported; the dependencies come from the venv's folder.
    `make wheel-check` does the whole thing: a clean venv, offline, every archive game.)"""
    unpacked = tmp_path / "unpacked"
    with zipfile.ZipFile(wheel) as archive:
        archive.extractall(unpacked)
    home = tmp_path / "home"
    home.mkdir()
    site_packages = next(p for p in sys.path if p.endswith("site-packages"))
    script = ("import gymnasium, octax_core, octax_gym\n"
              "print(octax_core.__file__)\n"
              "for game in ('SuperPong', 'DodgeArchive'):\n"
              "    env = gymnasium.make(octax_gym.env_id(game))\n"
              "    obs, _ = env.reset(seed=0)\n"
              "    print(game, obs.shape, env.step(1)[4]['score'])\n")
    env = {"HOME": str(home), "PATH": "/usr/bin:/bin", "PYTHONPATH": f"{unpacked}{os.pathsep}{site_packages}"}
    result = subprocess.run([sys.executable, "-S", "-c", script], cwd=tmp_path, env=env, capture_output=True,
                            text=True, timeout=300, check=False)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0] == str(unpacked / "octax_core" / "__init__.py")
    assert lines[1].startswith("SuperPong (4, 32, 64)") and lines[2].startswith("DodgeArchive (4, 64, 128)")
    assert not any(home.iterdir())
