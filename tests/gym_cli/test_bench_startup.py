"""benchmarks/startup.py: the plumbing and the output format, never a speed.

The real cases start JAX in three processes a run, so here they are swapped for `python -c pass`
and a failing command: what is checked is the BENCH line, the best-of choice and the refusals.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "benchmarks"))
import harness  # noqa: E402  (benchmarks/ is a folder of scripts, not a package)
import startup  # noqa: E402

QUICK = [sys.executable, "-c", "pass"]


def test_one_bench_line_with_each_case_and_the_ratio(monkeypatch, capsys):
    monkeypatch.setattr(startup, "CASES", {"import_octax_gym": QUICK, "cli_version": QUICK, "import_octax": QUICK})
    assert startup.main(["--repeats", "2"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("# python ") and "ml_dtypes " in out.splitlines()[0]
    (fields,) = harness.parse_bench_lines(out, "startup")
    assert list(fields) == ["import_octax_gym_s", "cli_version_s", "import_octax_s", "ratio", "ml_dtypes", "numpy",
                            "repeats", "load"]
    assert all(0 < float(fields[f"{name}_s"]) < 60 for name in startup.CASES)
    ratio = float(fields["import_octax_s"]) / float(fields["import_octax_gym_s"])
    assert float(fields["ratio"]) == pytest.approx(ratio, rel=0.15)  # the seconds are printed to the ms
    assert fields["repeats"] == "2" and fields["ml_dtypes"] != "na"


def test_without_octax_the_ratio_is_na(monkeypatch, capsys):
    monkeypatch.setattr(startup, "CASES", {"import_octax_gym": QUICK, "cli_version": QUICK,
                                           "import_octax": [sys.executable, "-c", "raise SystemExit(3)"]})
    assert startup.main(["--repeats", "1", "--no-octax"]) == 0
    (fields,) = harness.parse_bench_lines(capsys.readouterr().out, "startup")
    assert "import_octax_s" not in fields and fields["ratio"] == "na"


def test_a_failing_case_is_an_error_not_a_time(monkeypatch):
    monkeypatch.setattr(startup, "CASES", {"import_octax_gym": [sys.executable, "-c", "import no_such_module_here"]})
    with pytest.raises(SystemExit, match="no_such_module_here"):
        startup.main(["--repeats", "1", "--no-octax"])


def test_bad_repeats_are_refused(capsys):
    with pytest.raises(SystemExit) as exit:
        startup.main(["--repeats", "0"])
    assert exit.value.code == 2 and "--repeats must be at least 1, got 0" in capsys.readouterr().err
