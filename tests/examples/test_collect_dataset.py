"""examples/collect_dataset.py: collects a small Brix dataset, loads it and replays an episode exactly."""

import os
import subprocess
import sys
from pathlib import Path

from octax_core.env.romstore import search_dirs

REPO = Path(__file__).resolve().parents[2]


def test_collect_dataset_example_replays_an_episode_exactly(tmp_path):
    # HOME is a temporary folder so that nothing can land in the user's ~/.minari; that also hides
    # the user's ROM store (~/.local/share/octax-gym/roms, where `make demo` installs the octax
    # ROMs on a machine without ../shared), so the subprocess is pointed at every folder this
    # process searches, by absolute path, through OCTAX_ROM_DIR.
    rom_dirs = os.pathsep.join(str(folder) for folder in search_dirs())
    env = {**os.environ, "HOME": str(tmp_path), "OCTAX_ROM_DIR": rom_dirs}
    result = subprocess.run([sys.executable, "examples/collect_dataset.py", "--steps", "300", "--envs", "4"],
                            capture_output=True, text=True, timeout=300, cwd=REPO, env=env, check=False)
    assert result.returncode == 0, result.stderr
    collected, replayed = result.stdout.strip().splitlines()[-2:]
    assert collected.startswith("collected ") and " 300 steps in " in collected
    assert replayed.startswith("octax/Brix-example-v0: ") and replayed.endswith("replayed exactly: True")
    assert not (tmp_path / ".minari").exists()
    assert not any(tmp_path.iterdir()), sorted(p.name for p in tmp_path.iterdir())  # nothing under HOME at all
