"""benchmarks/skip_idle.py: a tiny run checks the plumbing, the exactness check and the page, never a speed."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "benchmarks"))
import harness  # noqa: E402  (benchmarks/ is a folder of scripts, not a package)


@pytest.mark.slow  # four compiles of a 30-ipf game (>20 s on 2 cores); CI's test-slow runs it
def test_skip_idle_prints_exact_rows_and_writes_the_page(tmp_path, octax_rom_dir):
    page, rows = tmp_path / "speed.md", tmp_path / "rows.jsonl"
    result = subprocess.run(
        [sys.executable, "benchmarks/skip_idle.py", "--games", "SlipperySlope", "--envs", "3", "--steps", "3",
         "--repeats", "1", "--markdown", str(page), "--jsonl", str(rows)],
        capture_output=True, text=True, timeout=600, cwd=REPO, check=False)
    assert result.returncode == 0, result.stderr
    (line,) = harness.parse_bench_lines(result.stdout, "skip_idle")
    assert line["game"] == "SlipperySlope" and line["n"] == "3" and line["exact"] == "True"
    assert int(line["plain_sps"]) > 0 and int(line["skip_sps"]) > 0
    text = page.read_text()
    assert "| SlipperySlope | archive | chip8 | 30 |" in text
    assert "python benchmarks/skip_idle.py --games SlipperySlope --envs 3 --steps 3 --repeats 1" in text
    assert str(rows) not in text and len(rows.read_text().splitlines()) == 1
