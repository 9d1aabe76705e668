"""The suite's own schedule: a fresh clone's first run hands out its longest files first.

pytest-xdist gives each worker whole files in the order it receives them; a long file handed out
last keeps one worker busy while the other has nothing left. tests/conftest.py orders files by
their recorded seconds, and a fresh clone (no .cache yet) by tests/file-seconds.json.
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import conftest

TESTS = Path(__file__).resolve().parent


def test_the_first_run_seconds_name_test_files_that_exist():
    seconds = json.loads((TESTS / "file-seconds.json").read_text())
    missing = [file for file in seconds if not (TESTS.parent / file).is_file()]
    assert not missing, f"tests/file-seconds.json names files that are gone: {missing}"
    assert all(isinstance(value, (int, float)) and value >= 0 for value in seconds.values())


def test_a_fresh_clone_runs_its_longest_files_first(monkeypatch, tmp_path):
    monkeypatch.setattr(conftest, "_FILE_SECONDS", tmp_path / "no-record-yet.json")
    seconds = json.loads((TESTS / "file-seconds.json").read_text())
    short, long = sorted(seconds, key=seconds.get)[0], sorted(seconds, key=seconds.get)[-1]
    items = [SimpleNamespace(nodeid=f"{short}::test_a"), SimpleNamespace(nodeid="tests/new_file.py::test_b"),
             SimpleNamespace(nodeid=f"{long}::test_c"), SimpleNamespace(nodeid=f"{short}::test_d")]
    conftest.pytest_collection_modifyitems(None, items)
    assert [item.nodeid for item in items] == ["tests/new_file.py::test_b", f"{long}::test_c",
                                               f"{short}::test_a", f"{short}::test_d"]


def test_this_clones_record_comes_before_the_committed_seconds(monkeypatch, tmp_path):
    seconds = json.loads((TESTS / "file-seconds.json").read_text())
    short, long = sorted(seconds, key=seconds.get)[0], sorted(seconds, key=seconds.get)[-1]
    record = tmp_path / "record.json"
    record.write_text(json.dumps({short: 10_000.0}))
    monkeypatch.setattr(conftest, "_FILE_SECONDS", record)
    items = [SimpleNamespace(nodeid=f"{long}::test_a"), SimpleNamespace(nodeid=f"{short}::test_b")]
    conftest.pytest_collection_modifyitems(None, items)
    assert [item.nodeid for item in items] == [f"{short}::test_b", f"{long}::test_a"]
