"""`octax-gym train --save-at-evals`: every evaluation also keeps each agent's params as
agents/<game>-seed<s>-step<N>.msgpack, and the dataset suite picks its medium and expert policies
from such a run (the suite's own tests, tests/gym_layer/test_dataset_suite.py, use fake runs)."""

from __future__ import annotations

import json

import pytest

pytest.importorskip("flax")
from octax_gym.datasets import suite  # noqa: E402
from tiny_run import ALGORITHM, LONE, STEPS, TOGETHER  # noqa: E402


def test_each_evaluation_keeps_its_agents_and_the_suite_picks_from_them(trained):
    run = trained(ALGORITHM, *LONE)
    names = sorted(p.name for p in (run / "agents").iterdir())
    assert names == sorted(["Deep8-seed1.msgpack", *(f"Deep8-seed1-step{step}.msgpack" for step in STEPS)])
    final = (run / "agents" / "Deep8-seed1.msgpack").read_bytes()
    assert (run / "agents" / f"Deep8-seed1-step{STEPS[-1]}.msgpack").read_bytes() == final
    assert (run / "agents" / f"Deep8-seed1-step{STEPS[1]}.msgpack").read_bytes() != final
    cards = suite.pick_policies(run, "Deep8")
    assert cards["expert"].params_path == run / "agents" / "Deep8-seed1.msgpack"
    assert cards["expert"].steps_trained == STEPS[-1] and cards["expert"].algorithm == ALGORITHM.upper()
    assert cards["medium"].steps_trained in STEPS[1:-1]  # part way through: never the untrained network
    assert json.loads((run / "config.json").read_text())["save_at_evals"] is True  # a --resume keeps it


def test_without_the_flag_only_the_last_agents_are_kept(trained):
    run = trained(ALGORITHM, *TOGETHER)
    assert not [p.name for p in (run / "agents").iterdir() if "-step" in p.name]
    with pytest.raises(FileNotFoundError, match="--save-at-evals"):
        suite.pick_policies(run, "Deep8")
