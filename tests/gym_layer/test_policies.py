"""One table of built-in policies (octax_gym/policies.py) for `video.record`, `collect_dataset`
and the commands that play a game by themselves. Nothing here builds an env."""

from __future__ import annotations

import argparse

import numpy as np
import pytest

from octax_gym import UnknownOptionError, cli, policies, video
from octax_gym.policies import POLICIES, check_policy, make_policy, policy_name


def test_the_table_holds_random_and_noop():
    assert list(POLICIES) == ["random", "noop"]


def test_random_is_uniform_and_follows_the_seed():
    first, again, other = (make_policy("random", 64, 3, seed)(None) for seed in (5, 5, 6))
    assert first.shape == (64,) and np.issubdtype(first.dtype, np.integer)
    assert set(first.tolist()) == {0, 1, 2}
    assert np.array_equal(first, again) and not np.array_equal(first, other)
    assert np.array_equal(make_policy(None, 64, 3, 5)(None), first)  # None means "random"


def test_noop_holds_no_key_and_a_function_is_played_as_given():
    assert np.array_equal(make_policy("noop", 4, 3, 0)(None), np.zeros(4, np.int64))

    def agent(obs):
        return obs

    assert make_policy(agent, 4, 3, 0) is agent
    assert [policy_name(p) for p in (None, "noop", agent)] == ["random", "noop", agent.__qualname__]


def test_an_unknown_policy_names_the_table():
    with pytest.raises(UnknownOptionError) as info:
        check_policy("greedy")
    assert str(info.value) == ("unknown policy 'greedy'; valid: None, 'random', 'noop', or a function from a "
                               "batch of observations to a batch of actions")


def test_video_and_datasets_refuse_an_unknown_policy_with_the_same_error(tmp_path, monkeypatch):
    minari = pytest.importorskip("minari")
    from octax_gym import datasets

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    errors = []
    for call in (lambda: video.record("Pong", tmp_path / "v.mp4", steps=1, policy="greedy", progress=False),
                 lambda: datasets.collect_dataset("Brix", "octax/Brix-x-v0", 1, policy="greedy", progress=False)):
        with pytest.raises(UnknownOptionError) as info:
            call()
        errors.append(str(info.value))
    assert errors[0] == errors[1] == str(UnknownOptionError("policy", "greedy", (None, *POLICIES),
                                                             policies.FUNCTION_HINT))
    assert not (tmp_path / "minari").exists() and minari is not None  # refused before anything was made


def test_video_and_datasets_play_from_the_one_table():
    from octax_gym.datasets import collect

    assert video.make_policy is collect.make_policy is policies.make_policy
    assert not hasattr(video, "POLICIES") and not hasattr(collect, "POLICIES")


@pytest.mark.parametrize("command", ["record", "trace", "dataset collect"])
def test_every_command_offers_the_table_s_names(command, capsys):
    with pytest.raises(SystemExit):
        cli.main([*command.split(), "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert all(name in text for name in POLICIES)


def test_trace_takes_exactly_the_table_s_names():
    commands = next(a for a in cli.build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    option = next(a for a in commands.choices["trace"]._actions if a.dest == "policy")
    assert tuple(option.choices) == tuple(POLICIES)
