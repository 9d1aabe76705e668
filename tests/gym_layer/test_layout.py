"""The user layer's folders (issue 40): envs/, step/ and integrations/ took modules that users and
old code import by their flat names (`octax_gym.vector`, `octax_gym.sb3`). Those names must keep
giving the same module objects, so that monkeypatching and isinstance hold across both spellings;
the package itself must name only the new paths; and the ways in (`import octax_gym`, `python -m`,
the console script, Gymnasium's entry points) must still start, without torch until asked."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
import tomllib
from pathlib import Path

import gymnasium as gym
import pytest

import octax_gym
from octax_gym import _MOVED

REPO = Path(__file__).resolve().parents[2]
GROUPS = ("envs", "step", "integrations")


def test_the_alias_table_names_every_moved_module_and_only_those():
    moved = {f"octax_gym.{group}.{path.stem}" for group in GROUPS
             for path in (REPO / "octax_gym" / group).glob("*.py") if path.stem != "__init__"}
    assert sorted(_MOVED.values()) == sorted(moved)
    assert all(old == f"octax_gym.{new.rsplit('.', 1)[1]}" for old, new in _MOVED.items())
    assert not any((REPO / "octax_gym" / f"{old.rsplit('.', 1)[1]}.py").exists() for old in _MOVED)


@pytest.mark.parametrize("old", sorted(_MOVED))
def test_an_old_name_imports_the_moved_module_itself(old):
    new = _MOVED[old]
    module = importlib.import_module(old)
    assert module is importlib.import_module(new) and sys.modules[old] is sys.modules[new]
    assert module.__name__ == new and module.__spec__.name == new  # it lives where it is, not at the alias
    short = old.rsplit(".", 1)[1]
    assert getattr(octax_gym, short) is module  # `from octax_gym import vector` and `octax_gym.vector`


def test_an_old_name_works_as_an_attribute_before_any_import():
    code = ("import sys, octax_gym\n"
            "assert 'octax_gym.env' not in sys.modules\n"
            "print(octax_gym.env is sys.modules['octax_gym.envs.env'], octax_gym.env.action_meanings.__module__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["True", "octax_gym.envs.env"]


def test_a_monkeypatch_through_an_old_name_reaches_the_new_module(monkeypatch):
    from octax_gym.envs import vector

    monkeypatch.setattr("octax_gym.vector.FRAMES_PER_SECOND", 61)
    assert vector.FRAMES_PER_SECOND == 61
    import octax_gym.vector as old

    assert old.OctaxVectorEnv is vector.OctaxVectorEnv  # one class: isinstance holds both ways


def test_the_new_folders_load_no_training_stack():
    code = ("import sys, octax_gym, octax_gym.envs, octax_gym.step, octax_gym.integrations, octax_gym.vector\n"
            "print(sorted(m for m in ('torch', 'stable_baselines3', 'torchrl', 'minari') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def _old_names_imported(path: Path) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [a.name for a in node.names if a.name in _MOVED]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            found += [name for name in names if name in _MOVED]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            target = node.value.split(":")[0]  # "octax_gym.vector" or an entry point "octax_gym.env:OctaxEnv"
            found += [node.value] if target in _MOVED and (":" in node.value or node.value == target) else []
    return [f"{path.relative_to(REPO)}: {name}" for name in found]


def test_no_module_of_the_package_goes_through_an_alias():
    modules = sorted((REPO / "octax_gym").rglob("*.py"))
    assert len(modules) > 50
    offences = [o for path in modules if path.name != "__init__.py" or path.parent.name != "octax_gym"
                for o in _old_names_imported(path)]
    assert not offences, offences
    assert not set(octax_gym._LAZY.values()) & set(_MOVED)


def test_gymnasium_entry_points_name_the_new_modules():
    specs = [spec for env_id, spec in gym.registry.items() if env_id.startswith(f"{octax_gym.NAMESPACE}/")]
    assert len(specs) > 10
    points = {point for spec in specs for point in (spec.entry_point, spec.vector_entry_point)}
    assert points == {"octax_gym.envs.env:OctaxEnv", "octax_gym.envs.vector:OctaxVectorEnv"}


def test_console_scripts_and_python_m_still_start():
    scripts = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]
    for target in scripts.values():
        module, attr = target.split(":")
        assert module not in _MOVED and callable(getattr(importlib.import_module(module), attr)), target
    script = Path(sys.executable).with_name("octax-gym")
    assert script.exists(), f"the console script is not installed beside {sys.executable}"
    version = subprocess.run([str(script), "--version"], capture_output=True, text=True, check=True).stdout
    assert version.split() == ["octax-gym", octax_gym.__version__]
    for module in ("octax_gym", "octax_gym.demo"):
        result = subprocess.run([sys.executable, "-m", module, "--help"], capture_output=True, text=True)
        assert result.returncode == 0 and "usage:" in result.stdout, (module, result.stderr[-2000:])
