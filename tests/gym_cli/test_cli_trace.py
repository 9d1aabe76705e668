"""`octax-gym trace` (octax_gym/cli/trace.py): the printed ranking, --csv, --plot and the errors.

Every Brix run here uses the same shape (300 steps x 4 envs), so the file compiles it once.
"""

from __future__ import annotations

import csv
import re
import sys

import pytest

from octax_gym import cli

BRIX = ["trace", "Brix", "--steps", "300", "--envs", "4"]


def _rows(out: str) -> list[list[str]]:
    """The ranking table's rows after its header, cells split on runs of 2+ spaces."""
    lines = out.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("role"))
    return [re.split(r"\s{2,}", line.strip(), maxsplit=4) for line in lines[start + 1:]
            if line and not line.startswith(("note:", "wrote"))]


def test_trace_prints_the_top_candidates_of_each_role(octax_rom_dir, capsys):
    assert cli.main(BRIX) == 0
    out = capsys.readouterr().out
    assert out.startswith("Brix: 300 steps x 4 envs, random policy, seed 0; with the game's reward and termination")
    assert re.search(r"\n\d+ episodes ended \(the game's rule\), 0 cut at the step limit", out)
    rows = _rows(out)
    assert [row[0] for row in rows] == ["score"] * 3 + ["lives"] * 3 + ["game over"] * 3
    best = {row[0]: row for row in rows if row[1] == "1"}
    assert best["score"][2] == "V5" and "moves with the reward (r=+1.00)" in best["score"][4]
    assert best["lives"][2] == "VE" and best["game over"][2] == "VE"
    assert "VE == 4 at 100% of ended steps" in best["game over"][4]
    assert all(0 < float(row[3]) <= 1 for row in rows)


def test_top_blind_and_gymnasium_id_in_any_case(octax_rom_dir, capsys):
    assert cli.main(["trace", "octax/brix-v0", "--steps", "300", "--envs", "4", "--blind", "--top", "1"]) == 0
    out = capsys.readouterr().out
    assert "blind: the game's keys and start-up, no reward" in out
    assert "(screen still for 30 steps)" in out
    assert _rows(out)[0][:3] == ["score", "1", "V5"]
    assert len([row for row in _rows(out) if row[0] == "score"]) == 1
    assert "note: no reward in the trace" in out


def test_csv_holds_every_register_of_every_role(octax_rom_dir, tmp_path, capsys):
    path = tmp_path / "out" / "ranking.csv"
    assert cli.main(BRIX + ["--csv", str(path)]) == 0
    assert f"wrote {path}" in capsys.readouterr().out
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 3 * 16
    assert {row["role"] for row in rows} == {"score", "lives", "game_over"}
    score = [row for row in rows if row["role"] == "score"]
    assert sorted(row["register"] for row in score) == sorted(f"V{k:X}" for k in range(16))
    assert score[0]["register"] == "V5" and score[0]["rank"] == "1" and float(score[0]["confidence"]) > 0.5


def test_plot_writes_a_png(octax_rom_dir, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    path = tmp_path / "brix.png"
    assert cli.main(BRIX + ["--plot", str(path), "--top", "2"]) == 0
    assert f"wrote {path}" in capsys.readouterr().out
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_raw_rom_file_is_traced_without_a_spec(counter_rom, capsys):
    assert cli.main(["trace", str(counter_rom), "--steps", "200", "--envs", "2"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("counter.ch8: 200 steps x 2 envs, random policy, seed 0; a raw ROM: all 16 keys")
    assert _rows(out)[0][:3] == ["score", "1", "V0"]
    assert "note: no episode ended in the trace" in out
    assert [row for row in _rows(out) if row[0] == "game over"] == [
        ["game over", "-", "-", "0.00", "no register shows any evidence"]]


def _error(argv, capsys) -> str:
    assert cli.main(argv) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    return captured.err


def test_unknown_game_or_missing_file_lists_the_valid_ids(capsys):
    err = _error(["trace", "Nope"], capsys)
    assert "octax-gym: error: unknown game 'Nope'; valid: 'Airplane'" in err
    assert "'Brix'" in err and "'Pong'" in err
    assert "the path of a ROM file (.ch8, .sc8, .xo8; there is no file 'Nope')" in err
    assert "unknown game 'missing.ch8'" in _error(["trace", "missing.ch8"], capsys)


def test_empty_rom_file_is_refused(tmp_path, capsys):
    (tmp_path / "empty.ch8").write_bytes(b"")
    assert "is empty" in _error(["trace", str(tmp_path / "empty.ch8")], capsys)


@pytest.mark.parametrize("option", ["--steps", "--envs", "--top"])
def test_counts_below_one_are_refused_before_anything_runs(option, capsys):
    assert f"{option} must be >= 1, got 0" in _error(["trace", "Brix", option, "0"], capsys)


def test_plot_file_must_be_png_and_needs_matplotlib(tmp_path, monkeypatch, capsys):
    assert "must end in .png, got" in _error(BRIX + ["--plot", str(tmp_path / "x.jpg")], capsys)
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib now raises ImportError
    err = _error(BRIX + ["--plot", str(tmp_path / "x.png")], capsys)
    assert "--plot needs matplotlib: pip install 'octax-gym[train]'" in err
    assert not (tmp_path / "x.png").exists()


def test_unknown_policy_is_a_usage_error_naming_the_choices(capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["trace", "Brix", "--policy", "greedy"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'greedy'" in err and "random" in err and "noop" in err
