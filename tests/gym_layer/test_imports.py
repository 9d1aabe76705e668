"""The import graph: `import octax_gym` loads no torch, SB3 or TorchRL; the adapters load on use."""

from __future__ import annotations

import subprocess
import sys

PROBE = """
import sys, octax_gym
heavy = sorted(m for m in ("torch", "stable_baselines3", "torchrl", "moviepy") if m in sys.modules)
print("loaded:", heavy)
octax_gym.make_torchrl_env
print("after:", "torchrl" in sys.modules)
"""


def test_import_octax_gym_loads_no_training_stack():
    out = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, check=True).stdout
    assert "loaded: []" in out and "after: True" in out


def test_unknown_attribute_is_an_attribute_error():
    import octax_gym

    try:
        octax_gym.make_rllib_env
    except AttributeError as exc:
        assert "make_rllib_env" in str(exc)
    else:
        raise AssertionError("expected AttributeError")
