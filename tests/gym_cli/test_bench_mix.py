"""benchmarks/mix.py: a tiny run checks the plumbing and the output format, never a speed."""

from __future__ import annotations

import pytest
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "benchmarks"))
import harness  # noqa: E402  (benchmarks/ is a folder of scripts, not a package)


def _run(*argv):
    return subprocess.run([sys.executable, "benchmarks/mix.py", *argv], capture_output=True, text=True,
                          timeout=600, cwd=REPO, check=False)


@pytest.mark.slow  # a long check (>20 s on 2 cores); CI's test-slow runs it
def test_mix_prints_each_game_and_the_mix_against_their_mean(octax_rom_dir):
    result = _run("--games", "Pong,Brix", "--envs", "4", "--steps", "2", "--repeats", "1")
    assert result.returncode == 0, result.stderr
    games = harness.parse_bench_lines(result.stdout, "mix_game")
    assert [line["game"] for line in games] == ["Pong", "Brix"]
    mix, = harness.parse_bench_lines(result.stdout, "mix")
    mean = (int(games[0]["sps"]) + int(games[1]["sps"])) / 2
    assert abs(int(mix["single_mean_sps"]) - mean) <= 1
    assert abs(float(mix["ratio"]) - int(mix["mix_sps"]) / int(mix["single_mean_sps"])) < 0.002
    assert float(mix["single_compile_s"]) > 0 and float(mix["mix_compile_s"]) > 0 and mix["games"] == "2"


def test_mix_usage_errors():
    result = _run("--games", "Pong,Rockto", "--envs", "4", "--steps", "1", "--repeats", "1")
    assert result.returncode == 1 and "one platform, got several (chip8: Pong; schip: Rockto)" in result.stderr
    result = _run("--games", "Pong,Brix,Tetris", "--envs", "2")
    assert result.returncode == 2 and "--envs must be >= the number of games (3)" in result.stderr
