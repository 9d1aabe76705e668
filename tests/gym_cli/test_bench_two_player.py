"""benchmarks/two_player.py: a tiny run checks the plumbing and the output format, never a speed."""

from __future__ import annotations

import pytest
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "benchmarks"))
import harness  # noqa: E402  (benchmarks/ is a folder of scripts, not a package)


def _run(*argv):
    return subprocess.run([sys.executable, "benchmarks/two_player.py", *argv], capture_output=True, text=True,
                          timeout=300, cwd=REPO, check=False)


@pytest.mark.slow  # a long check (>20 s on 2 cores); CI's test-slow runs it
def test_two_player_prints_one_line_per_game_and_n_with_both_sides(octax_rom_dir):
    result = _run("--games", "SpaceRacer", "--envs", "2,3", "--steps", "2", "--repeats", "1")
    assert result.returncode == 0, result.stderr
    lines = harness.parse_bench_lines(result.stdout, "two_player")
    assert [(line["game"], line["n"]) for line in lines] == [("SpaceRacer", "2"), ("SpaceRacer", "3")]
    for line in lines:
        assert int(line["one_sps"]) > 0 and int(line["two_sps"]) > 0 and line["device"] == "cpu"
        assert abs(float(line["ratio"]) - int(line["two_sps"]) / int(line["one_sps"])) < 0.002


def test_two_player_usage_errors():
    result = _run("--games", "Pong")
    assert result.returncode == 2 and "not two-player game(s): ['Pong']; valid: " in result.stderr
    assert "SpaceRacer" in result.stderr
    result = _run("--envs", "x")
    assert result.returncode == 2 and "--envs must be comma-separated positive integers" in result.stderr
