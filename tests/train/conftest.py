"""Runs shared by tests/train's modules.

Compiling the trainer is what its tests pay for (tens of seconds a program on two cores; running
the tiny runs takes well under a second), so every module trains with the one tiny config `tiny_run.TINY`
(the same programs, read back from JAX's persistent cache after their first compile) and a run
that several checks read is trained once a session by `trained` (`tiny_run.TOGETHER` and `LONE`,
of one algorithm, `tiny_run.ALGORITHM`; the multi-task run of `tiny_run.multitask_flags` on the
session's dodger `archive`): the lone run of (Deep8, seed 1) is the run a many-agent run's agent
must equal, the run test_resume cuts and resumes and the one the dataset suite picks policies
from. Tests read these folders and never write into them (they copy one to change it).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tiny_run import TINY


@pytest.fixture(scope="session")
def trained(tmp_path_factory):
    """`trained(algorithm, *flags) -> OUT`: the folder of `octax-gym train ALGO *flags` with TINY
    (`flags` after TINY's, so a run may change one of them), trained once a session for each
    distinct command."""
    pytest.importorskip("flax")
    from octax_gym.cli import main

    runs: dict = {}

    def run(algorithm: str, *flags: str) -> Path:
        if (algorithm, flags) not in runs:
            out = tmp_path_factory.mktemp(algorithm) / "run"
            assert main(["train", algorithm, *TINY, *flags, "--out-dir", str(out)]) == 0
            runs[algorithm, flags] = out
        return runs[algorithm, flags]

    return run


@pytest.fixture(scope="session")
def archive(tmp_path_factory):
    """A dodger archive of 6 variants, all accepted (the checks faked, as tests/generate's archive
    fixture fakes them: their verdicts are not what is tested here); seed 0's six dodgers hold
    both splits (3 train, 3 test)."""
    pytest.importorskip("flax")
    from octax_core.generate import filters, rounds
    from octax_core.generate.families import get_family
    from octax_gym.cli.generate import write_round
    from octax_gym.generated import load_archive

    folder = tmp_path_factory.mktemp("archive")
    candidates = rounds.family_candidates(get_family("dodger"), 6, 0)

    def fake_check(specs, roms, settings):
        return [filters.Verdict((), 1.0, 0.5, 3.0) for _ in specs]
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(filters, "check", fake_check)
        write_round(folder, candidates, filters.Settings(), {"family": "dodger"})
    assert len(load_archive(folder, "train")) == 3 and len(load_archive(folder, "test")) == 3
    return folder
