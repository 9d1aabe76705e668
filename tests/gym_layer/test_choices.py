"""One error type for an unknown name (octax_gym/envs/choices.py), raised by every place that takes one.

The error's own wording is checked first; then every unknown-name path of the user layer, each
raising `UnknownOptionError` with the bad value and the valid choices. Most paths fail before an
env is built, so only the reset-option cases compile (the Counter game, shared with
test_bad_arguments.py).
"""

from __future__ import annotations

import numpy as np
import pytest

import octax_gym
from counter_game import COUNTER
from octax_gym import OctaxEnv, OctaxVectorEnv, UnknownOptionError, scores, video
from octax_gym.envs import render
from octax_gym.envs.choices import check_choice, check_names


def test_the_message_names_the_value_the_close_matches_and_every_choice():
    with pytest.raises(UnknownOptionError) as info:
        check_choice("backend", "nunpy", ("numpy", "jax", "torch"))
    assert str(info.value) == "unknown backend 'nunpy' (did you mean 'numpy'?); valid: 'numpy', 'jax', 'torch'"
    assert (info.value.what, info.value.value, info.value.choices) == ("backend", "nunpy", ("numpy", "jax", "torch"))


def test_it_is_a_value_error_and_a_key_error_printed_plainly():
    error = UnknownOptionError("policy", "greedy", (None, "random"), "or a function")
    assert isinstance(error, ValueError) and isinstance(error, KeyError)
    assert str(error) == "unknown policy 'greedy'; valid: None, 'random', or a function"  # no KeyError quotes
    assert octax_gym.UnknownOptionError is UnknownOptionError


def test_check_choice_returns_a_valid_value_and_refuses_bools_and_arrays():
    assert check_choice("render_mode", None, (None, "rgb_array")) is None
    with pytest.raises(UnknownOptionError, match="unknown obs_scale True"):
        check_choice("obs_scale", True, (1, 255))  # 1 == True, but a bool is no scale
    with pytest.raises(UnknownOptionError, match=r"unknown policy array"):
        check_choice("policy", np.zeros(2), (None, "random"))


def test_check_names_lists_every_unknown_name_sorted():
    check_names("reset option(s)", {"reset_mask": 1}, ("reset_mask",))
    with pytest.raises(UnknownOptionError, match=r"unknown env option\(s\) \['b', 'noop_mx'\] "
                                                 r"\(did you mean 'noop_max'\?\); valid: 'noop_max'$"):
        check_names("env option(s)", ["noop_mx", "b"], ("noop_max",))


@pytest.mark.parametrize("keyword, value, message", [
    ("backend", "tensorflow", "unknown backend 'tensorflow'; valid: 'numpy', 'jax', 'torch'"),
    ("render_mode", "human", "unknown render_mode 'human'; valid: None, 'rgb_array'"),
    ("autoreset_mode", "sometimes", "unknown autoreset_mode 'sometimes'; valid: 'next_step', 'same_step', 'disabled'"),
    ("palette", "purpel", "unknown palette 'purpel'; valid: 'white', 'octo', 'green', 'amber', 'blue', or an"),
    ("device", "quantum", "unknown or unavailable device 'quantum'; valid: "),
])
def test_every_unknown_env_keyword_value_raises_it(keyword, value, message):
    with pytest.raises(UnknownOptionError) as info:
        OctaxVectorEnv("Pong", 2, **{keyword: value})  # refused before anything is built
    assert str(info.value).startswith(message) and info.value.value == value


def test_an_unknown_game_raises_it_from_every_entry_point(tmp_path):
    for make in (lambda: OctaxVectorEnv("Pongg", 2), lambda: OctaxEnv("Pongg"),
                 lambda: video.record("Pongg", tmp_path / "v.mp4", steps=1, progress=False)):
        with pytest.raises(UnknownOptionError, match=r"^unknown game 'Pongg' \(did you mean 'Pong'\?\)"):
            make()


def test_unknown_policy_palette_and_scored_game_raise_it(tmp_path):
    with pytest.raises(UnknownOptionError, match="unknown policy 'greedy'"):
        video.record("Pong", tmp_path / "v.mp4", steps=1, policy="greedy", progress=False)
    with pytest.raises(UnknownOptionError, match="unknown palette 'mauve'"):
        render.resolve_palette("mauve")
    with pytest.raises(UnknownOptionError, match="unknown scored game 'NoSuchGame'"):
        scores.normalized_score("NoSuchGame", 1.0)


def test_unknown_dataset_options_raise_it():
    pytest.importorskip("minari")
    from octax_gym.datasets import collect_dataset

    for change, message in (({"policy": "greedy"}, "unknown policy 'greedy'"),
                            ({"noop_mx": 3}, r"unknown env option\(s\) \['noop_mx'\]")):
        with pytest.raises(UnknownOptionError, match=message):
            collect_dataset("Brix", "octax/Brix-never-v0", 3, num_envs=3, progress=False, **change)


def test_unknown_reset_options_raise_it(counter_rom):
    envs = OctaxVectorEnv(COUNTER, 3, rom=counter_rom)
    envs.reset(seed=0)
    with pytest.raises(UnknownOptionError, match=r"unknown reset option\(s\) \['bogus'\]; valid: 'reset_mask'"):
        envs.reset(options={"bogus": 1})
    env = OctaxEnv(COUNTER, rom=counter_rom)
    with pytest.raises(UnknownOptionError, match=r"unknown reset option\(s\) \['reset_mask'\]; valid: none"):
        env.reset(seed=0, options={"reset_mask": np.ones(1, bool)})
