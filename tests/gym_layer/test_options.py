"""The Gymnasium layer takes the core's options from one place (`octax_core.env.config`).

Every field of `EnvConfig` and `EnvParams` but `autoreset` must be a keyword of the vector and
the single env, and must reach the core env it builds: a field added to the dataclasses and not
wired through would fail here, with no list of names in this file to keep in step.
"""

from __future__ import annotations

import dataclasses

import pytest

from counter_game import COUNTER
from octax_core.env.config import ENV_OPTIONS, EnvConfig, EnvParams, make_config
from octax_gym import OctaxEnv, OctaxVectorEnv
from octax_gym.envs.env import SINGLE_KEYWORDS
from octax_gym.envs.vector import KEYWORDS

GYM_OPTIONS = [name for name in ENV_OPTIONS if name != "autoreset"]  # autoreset_mode replaces it


def _other_value(field: dataclasses.Field):
    """A value the field's check accepts that differs from the default `make_config` gives."""
    default = getattr(make_config(COUNTER)[0 if field.name in EnvConfig.__dataclass_fields__ else 1], field.name)
    default = default.item() if hasattr(default, "item") else default
    candidates = [not default] if isinstance(default, bool) else [default + 1, 255, 0.5, 3]
    for value in candidates:
        try:
            field.metadata["check"](field.name, value)
        except (TypeError, ValueError):
            continue
        if value != default:
            return value
    raise AssertionError(f"no non-default value found for option {field.name}")


FIELDS = {field.name: field for field in dataclasses.fields(EnvConfig) + dataclasses.fields(EnvParams)}


def test_the_options_are_the_dataclass_fields():
    assert set(ENV_OPTIONS) == set(FIELDS)
    assert set(GYM_OPTIONS) <= set(KEYWORDS) and "autoreset" not in KEYWORDS
    assert set(GYM_OPTIONS) <= set(SINGLE_KEYWORDS) and "autoreset_mode" not in SINGLE_KEYWORDS


@pytest.mark.parametrize("name", GYM_OPTIONS)
def test_each_option_reaches_the_core_env(name, counter_rom):
    value = _other_value(FIELDS[name])
    # mirror is a two-player env's option (games with mirrored seats): one seat against an opponent
    game, where = ("Cycles", {"opponent": "noop"}) if name == "mirror" else (COUNTER, {"rom": counter_rom})
    for env in (OctaxVectorEnv(game, 2, **where, **{name: value}), OctaxEnv(game, **where, **{name: value})._vector):
        held = getattr(env.core_env.config, name) if name in EnvConfig.__dataclass_fields__ else getattr(env.params, name)
        assert (held.item() if hasattr(held, "item") else held) == pytest.approx(value)
