"""Runs shared by tests/train's modules.

Compiling the trainer is what its tests pay for (tens of seconds a program on two cores; running
the tiny runs takes well under a second), so every module trains with the one tiny config `tiny_run.TINY`
(the same programs, read back from JAX's persistent cache after their first compile) and a run
that several checks read is trained once a session by `trained` (`tiny_run.TOGETHER` and `LONE`):
the lone PPO run of (Deep8, seed 1) is the run a many-agent run's agent must equal, the run
test_resume cuts and resumes and the one the dataset suite picks policies from. Tests read these
folders and never write into them (they copy one to change it).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tiny_run import TINY


@pytest.fixture(scope="session")
def trained(tmp_path_factory):
    """`trained(algorithm, *flags) -> OUT`: the folder of `octax-gym train ALGO *flags` with TINY,
    trained once a session for each distinct command."""
    pytest.importorskip("flax")
    from octax_gym.cli import main

    runs: dict = {}

    def run(algorithm: str, *flags: str) -> Path:
        if (algorithm, flags) not in runs:
            out = tmp_path_factory.mktemp(algorithm) / "run"
            assert main(["train", algorithm, *flags, *TINY, "--out-dir", str(out)]) == 0
            runs[algorithm, flags] = out
        return runs[algorithm, flags]

    return run
