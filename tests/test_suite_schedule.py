"""The suite's own schedule: a fresh clone's first run hands out its longest files first.

pytest-xdist gives each worker whole files in the order it receives them; a long file handed out
last keeps one worker busy while the other has nothing left. tests/conftest.py orders files by
their recorded seconds, and a fresh clone (no .cache yet) by tests/file-seconds.json.
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import pytest

TESTS = Path(__file__).resolve().parent


@pytest.fixture
def conftest(request):
    """tests/conftest.py as pytest loaded it (`import conftest` could find a folder's conftest)."""
    for plugin in request.config.pluginmanager.get_plugins():
        if Path(getattr(plugin, "__file__", "") or "").resolve() == TESTS / "conftest.py":
            return plugin
    raise AssertionError("tests/conftest.py is not loaded")


def test_the_first_run_seconds_name_test_files_that_exist():
    seconds = json.loads((TESTS / "file-seconds.json").read_text())
    missing = [file for file in seconds if not (TESTS.parent / file).is_file()]
    assert not missing, f"tests/file-seconds.json names files that are gone: {missing}"
    assert all(isinstance(value, (int, float)) and value >= 0 for value in seconds.values())


def test_a_fresh_clone_runs_its_longest_files_first(conftest, monkeypatch, tmp_path):
    monkeypatch.setattr(conftest, "_FILE_SECONDS", tmp_path / "no-record-yet.json")
    seconds = json.loads((TESTS / "file-seconds.json").read_text())
    short, long = sorted(seconds, key=seconds.get)[0], sorted(seconds, key=seconds.get)[-1]
    items = [SimpleNamespace(nodeid=f"{short}::test_a"), SimpleNamespace(nodeid="tests/new_file.py::test_b"),
             SimpleNamespace(nodeid=f"{long}::test_c"), SimpleNamespace(nodeid=f"{short}::test_d")]
    conftest.pytest_collection_modifyitems(None, items)
    assert [item.nodeid for item in items] == ["tests/new_file.py::test_b", f"{long}::test_c",
                                               f"{short}::test_a", f"{short}::test_d"]


def test_this_clones_record_comes_before_the_committed_seconds(conftest, monkeypatch, tmp_path):
    seconds = json.loads((TESTS / "file-seconds.json").read_text())
    short, long = sorted(seconds, key=seconds.get)[0], sorted(seconds, key=seconds.get)[-1]
    record = tmp_path / "record.json"
    record.write_text(json.dumps({short: 10_000.0}))
    monkeypatch.setattr(conftest, "_FILE_SECONDS", record)
    items = [SimpleNamespace(nodeid=f"{long}::test_a"), SimpleNamespace(nodeid=f"{short}::test_b")]
    conftest.pytest_collection_modifyitems(None, items)
    assert [item.nodeid for item in items] == [f"{short}::test_b", f"{long}::test_a"]


def test_the_train_files_are_one_unit_of_work_and_the_others_their_file(conftest):
    unit = conftest.work_unit
    assert unit("tests/train/test_resume.py::test_a") == unit("tests/train/test_many_agents.py::test_b[x]") == "tests/train/"
    assert unit("tests/core_env/test_mix.py::test_c") == "tests/core_env/test_mix.py"


def test_loadfile_hands_out_the_units(conftest, request, monkeypatch):
    pytest.importorskip("xdist")
    options = {"dist": "loadfile", "tx": ["2*popen"]}  # as `-n 2 --dist loadfile` sets them
    monkeypatch.setattr(request.config, "getvalue", options.get)
    scheduler = conftest.pytest_xdist_make_scheduler(request.config, None)
    assert scheduler._split_scope("tests/train/test_resume.py::test_a") == "tests/train/"
    assert scheduler._split_scope("tests/gym_layer/test_sb3.py::test_b") == "tests/gym_layer/test_sb3.py"
    options["dist"] = "load"
    assert conftest.pytest_xdist_make_scheduler(request.config, None) is None  # xdist's own for other modes


def test_a_units_files_are_ordered_by_the_units_seconds(conftest, monkeypatch, tmp_path):
    record = tmp_path / "record.json"
    record.write_text(json.dumps({"tests/train/test_a.py": 30.0, "tests/train/test_b.py": 30.0,
                                  "tests/core_env/test_c.py": 50.0}))
    monkeypatch.setattr(conftest, "_FILE_SECONDS", record)
    monkeypatch.setattr(conftest, "_FIRST_RUN_SECONDS", tmp_path / "none.json")
    items = [SimpleNamespace(nodeid=n) for n in
             ("tests/core_env/test_c.py::t1", "tests/train/test_a.py::t2", "tests/train/test_b.py::t3")]
    conftest.pytest_collection_modifyitems(None, items)
    assert [item.nodeid.split("::")[1] for item in items] == ["t2", "t3", "t1"]  # 60 s of train before 50
