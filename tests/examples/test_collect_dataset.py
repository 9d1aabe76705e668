"""examples/collect_dataset.py: collects a small Brix dataset, loads it and replays an episode exactly."""

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def test_collect_dataset_example_replays_an_episode_exactly(tmp_path):
    env = {**os.environ, "HOME": str(tmp_path)}  # nothing may land in the user's ~/.minari
    result = subprocess.run([sys.executable, "examples/collect_dataset.py", "--steps", "300", "--envs", "4"],
                            capture_output=True, text=True, timeout=300, cwd=REPO, env=env, check=False)
    assert result.returncode == 0, result.stderr
    collected, replayed = result.stdout.strip().splitlines()[-2:]
    assert collected.startswith("collected ") and " 300 steps in " in collected
    assert replayed.startswith("octax/Brix-example-v0: ") and replayed.endswith("replayed exactly: True")
    assert not (tmp_path / ".minari").exists()
