"""`octax-gym generate`: the families listed, an archive written, the same one for the same seed."""

import json

import pytest

from octax_core.generate import archive, rounds
from octax_gym.cli import main

TINY = ["--frames", "400", "--end-limit", "100", "--horizon", "40", "--beam", "2", "--random-lanes", "1"]


def test_list_families(capsys):
    assert main(["generate", "--list-families"]) == 0
    out = capsys.readouterr().out
    for name in ("dodger", "catcher", "paddle"):
        assert f"\n{name} " in f"\n{out}"
    assert "test split: fall in [3]" in out


def test_bad_usage_names_the_choices(capsys, tmp_path):
    assert main(["generate", "--family", "pacman", "--out", str(tmp_path)]) == 1
    assert "unknown family 'pacman'; valid: dodger, catcher, paddle" in capsys.readouterr().err
    assert main(["generate", "--family", "dodger"]) == 1
    assert "needs --family F and --out DIR" in capsys.readouterr().err
    assert main(["generate", "--family", "dodger", "--out", str(tmp_path), "--count", "0"]) == 1
    assert "--count must be >= 1, got 0" in capsys.readouterr().err


def _run(folder, seed=5):
    return main(["generate", "--family", "paddle", "--count", "3", "--seed", str(seed), "--out", str(folder), *TINY])


def test_a_run_writes_sources_roms_and_the_archive(tmp_path, capsys):
    assert _run(tmp_path) == 0
    assert "of 3 accepted" in capsys.readouterr().out
    games = archive.read(tmp_path)["games"]
    assert [g["name"] for g in games] == ["paddle-s5-0000", "paddle-s5-0001", "paddle-s5-0002"]
    for game in games:
        assert set(archive.REQUIRED) <= set(game)
        assert (tmp_path / game["rom"]).read_bytes()  # the ROM and its source are beside it
        assert (tmp_path / game["source"]).read_text().startswith("\n####")
        assert game["split"] == ("test" if game["params"]["speed_x"] == 3 else "train")
        assert game["accepted"] == (game["reasons"] == [])
        assert game["random_score"] is not None and game["reference_score"] is not None


def test_the_same_seed_writes_the_same_archive(tmp_path):
    # the same programs as the test above: the second and third runs compile nothing new
    assert _run(tmp_path / "a") == 0 and _run(tmp_path / "b") == 0
    assert (tmp_path / "a" / archive.ARCHIVE).read_bytes() == (tmp_path / "b" / archive.ARCHIVE).read_bytes()


def test_judge_names_a_repeat_and_a_program_that_does_not_assemble():
    unassembled = rounds.Candidate("broken", "llm", {}, ": main\n\tjump nowhere\n", None, error="line 2: ...")
    rows = rounds.judge([unassembled])  # nothing runs: no batch is built
    assert rows[0]["reasons"] == ["does not assemble: line 2: ..."] and rows[0]["sha1"] is None


def test_read_refuses_a_damaged_archive(tmp_path):
    with pytest.raises(ValueError, match="no archive at"):
        archive.read(tmp_path)
    (tmp_path / archive.ARCHIVE).write_text(json.dumps({"version": 1, "games": [{"name": "x"}]}))
    with pytest.raises(ValueError, match="game 0 lacks family"):
        archive.read(tmp_path)


def test_judge_runs_a_repeated_program_once(monkeypatch):
    from octax_core.generate import filters

    batches = []

    def fake_check(specs, roms, settings):
        batches.append([spec.id for spec in specs])
        return [filters.Verdict((), 1.0, 0.5, 3.0) for _ in specs]
    monkeypatch.setattr(filters, "check", fake_check)
    family_rows = rounds.family_candidates(rounds_family(), 2, 0)
    twin = rounds.Candidate("twin", "dodger", {}, family_rows[0].source, family_rows[0].rom)
    rows = rounds.judge([*family_rows, twin])
    assert batches == [[family_rows[0].name, family_rows[1].name]]  # one batch, the repeat left out
    assert rows[2]["reasons"] == [f"the same program as {family_rows[0].name}"] and not rows[2]["accepted"]
    assert rows[0]["accepted"] and rows[0]["reference_score"] == 3.0


def rounds_family():
    from octax_core.generate.families import get_family

    return get_family("dodger")
