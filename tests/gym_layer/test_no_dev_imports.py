"""The library stands alone: no module of octax_gym imports from the repository's examples/ or
benchmarks/ (scripts a wheel does not ship), nor puts either on sys.path to reach them. Read from
every module's source (its import statements, `importlib.import_module` of a named module and any
edit of sys.path, which is how a module would reach a script folder), so a lazy import inside a
function counts too."""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SCRIPT_FOLDERS = ("examples", "benchmarks")


def _script_modules() -> set[str]:
    names = {p.stem for folder in SCRIPT_FOLDERS for p in (REPO / folder).glob("*.py")}
    return names | set(SCRIPT_FOLDERS)


def _offences(path: Path, scripts: set[str]) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [f"import {a.name}" for a in node.names if a.name.split(".")[0] in scripts]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module.split(".")[0] in scripts:
            found.append(f"from {node.module} import ...")
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
              and isinstance(node.func.value, ast.Attribute) and node.func.value.attr == "path"
              and isinstance(node.func.value.value, ast.Name) and node.func.value.value.id == "sys"):
            found.append(f"sys.path.{node.func.attr}(...)")
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "import_module"
              and node.args and isinstance(node.args[0], ast.Constant)
              and str(node.args[0].value).split(".")[0] in scripts):
            found.append(f"importlib.import_module({node.args[0].value!r})")
    return [f"{path.relative_to(REPO)}:{node}" for node in found]


def test_no_module_of_octax_gym_reaches_into_examples_or_benchmarks():
    scripts = _script_modules()
    assert {"throughput", "harness", "collect_dataset"} <= scripts  # the folders were read
    modules = sorted((REPO / "octax_gym").rglob("*.py"))
    assert len(modules) > 50
    offences = [o for path in modules for o in _offences(path, scripts)]
    assert not offences, offences
