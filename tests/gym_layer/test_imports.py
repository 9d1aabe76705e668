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


def test_the_public_names_stay_where_users_import_them():
    """The layout moved modules into subpackages; these top-level names must not move with them."""
    import octax_core
    import octax_gym
    import octax_gym.sb3
    import octax_gym.torchrl

    for name in ("Machine", "Quirks", "make", "list_games", "get_spec", "snapshot", "poke", "assemble", "disassemble"):
        assert callable(getattr(octax_core, name)), name
    for name in ("OctaxEnv", "OctaxVectorEnv", "InvalidActionError", "UnknownOptionError", "make_sb3_vec_env",
                 "make_torchrl_env"):
        assert getattr(octax_gym, name) is not None, name
    assert callable(octax_gym.sb3.make_sb3_vec_env) and callable(octax_gym.torchrl.make_torchrl_env)
    import octax_gym.datasets
    import octax_gym.scores

    assert octax_gym.collect_dataset is octax_gym.datasets.collect_dataset
    for name in ("iqm", "stratified_bootstrap_ci", "aggregate", "normalized_score", "score_table"):
        assert callable(getattr(octax_gym.scores, name)), name
    assert sorted(octax_core.PLATFORMS) == ["chip8", "schip", "xochip"] and octax_core.Platform is not None
    assert callable(octax_core.emulator.quirks_from_octo)
