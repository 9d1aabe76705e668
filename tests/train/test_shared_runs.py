"""tests/work_units.py's unit is every file that asks for the `trained` runs, and no other."""

from __future__ import annotations

import ast
from pathlib import Path

from work_units import SHARED_RUN_FILES, SHARED_RUN_UNIT, work_unit

REPO = Path(__file__).resolve().parents[2]


def files_asking_for(fixture: str) -> set[str]:
    """The test files with a function (test or fixture) that takes `fixture` as an argument."""
    found = set()
    for path in (REPO / "tests").rglob("test_*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef) and fixture in [a.arg for a in node.args.args]:
                found.add(path.relative_to(REPO).as_posix())
    return found


def test_the_unit_holds_exactly_the_files_that_ask_for_the_trained_runs():
    assert files_asking_for("trained") == set(SHARED_RUN_FILES)


def test_those_files_share_one_unit_and_every_other_file_is_its_own():
    assert {work_unit(file) for file in SHARED_RUN_FILES} == {SHARED_RUN_UNIT}
    for file in ("tests/train/test_selfplay.py", "tests/train/test_parts.py", "tests/core_env/test_env.py"):
        assert work_unit(file) == file
