"""The env's options, declared once: `EnvConfig` (fixed when the program is traced) and
`EnvParams` (values the compiled program takes as arguments).

Every option is a dataclass field whose metadata holds its check; `make_config` reads the fields
to know the valid names and to check the values, and the Gymnasium layer takes the same names
from `ENV_OPTIONS`. Adding an option is adding a field here (and using it), plus its docs.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, Callable

import jax
import jax.numpy as jnp

from octax_core.env.games import GameSpec, get_spec, list_games
from octax_core.validate import check_bool, check_choice, check_int, check_probability

OBS_SCALES = (1, 255)


def _option(default: Any, check: Callable[[str, Any], Any], dtype: Any = None) -> Any:
    """A field: its default, the check its value passes and, for a param, its array dtype."""
    return dataclasses.field(default=default, metadata={"check": check, "dtype": dtype})


@dataclasses.dataclass(frozen=True)
class EnvConfig:
    """What `make` fixes for the compiled program (changing one means a new compile).

    Attributes:
        frames_per_step: 60 Hz frames per env step; the observation holds the screen after each.
        instructions_per_frame: CHIP-8 instructions per frame; `make` takes the game's own
            (`GameSpec.instructions_per_frame`, an archive game's tickrate) where it names one.
        obs_scale: lit pixels read 1 (default) or 255.
        freeze_timers: zero both timers after each step (the octax package's `disable_delay`);
            `make` takes the game's own setting (`GameSpec.freeze_timers`) unless told.
        noop_max: each episode starts after 0..noop_max no-op steps, drawn uniformly (the ALE
            protocol uses 30). The start states are made once, at `make` (see `octax_core.env.starts`).
        autoreset: `step` starts a new episode as soon as one ends (same-step; the ended
            episode's last observation and info go in `info`), for `lax.scan` training loops.
        skip_idle: fast-forward the rest of a frame once the program provably spins, and give
            each env of a batch its own frame clock (`octax_core.emulator.idle`): the same
            observations, rewards and flags, bit for bit, at a cost that follows the work.
        mirror: two-player envs (`make_multi`) of a game whose sides mirror each other
            (`Seats.mirror`): seat 1 sees the screen flipped across the game's axis and its
            actions are mapped through `Seats.mirror_actions`, so one network plays both seats
            from the same side; scores and rewards are untouched. `make_multi` refuses it for
            other games, the one-player envs always.
    """

    frames_per_step: int = _option(4, check_int)
    instructions_per_frame: int = _option(11, check_int)
    obs_scale: int = _option(1, functools.partial(check_choice, choices=OBS_SCALES))
    freeze_timers: bool = _option(False, check_bool)
    noop_max: int = _option(0, functools.partial(check_int, minimum=0))
    autoreset: bool = _option(False, check_bool)
    skip_idle: bool = _option(True, check_bool)
    mirror: bool = _option(False, check_bool)


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class EnvParams:
    """Values the compiled program takes as arguments: change them (or vmap over them) freely.

    Attributes:
        max_episode_steps: () int32, truncation bound in env steps; `make` takes the game's
            own (`GameSpec.max_episode_steps`) unless told.
        repeat_action_probability: () float32, sticky actions (Machado et al., 2018): each step
            repeats the previous action with this probability.
    """

    max_episode_steps: jax.Array = _option(dataclasses.MISSING, check_int, jnp.int32)
    repeat_action_probability: jax.Array = _option(0.0, check_probability, jnp.float32)


CONFIG_OPTIONS = tuple(field.name for field in dataclasses.fields(EnvConfig))
PARAM_OPTIONS = tuple(field.name for field in dataclasses.fields(EnvParams))
ENV_OPTIONS = CONFIG_OPTIONS + PARAM_OPTIONS  # every keyword `make` takes besides the game and rom


def check_option_names(names, valid=ENV_OPTIONS, who: str = "make") -> None:
    """Raises TypeError naming the unknown keywords in `names` and listing the `valid` ones."""
    unknown = sorted(set(names) - set(valid))
    if unknown:
        raise TypeError(f"{who} got unknown keyword(s) {unknown}; valid: {', '.join(valid)}")


def make_config(spec: GameSpec, **options: Any) -> tuple[EnvConfig, EnvParams]:
    """The checked `EnvConfig` and `EnvParams` for `spec` and the given options; boots nothing.

    An option left out, or given as None, takes its default (for `freeze_timers`,
    `max_episode_steps` and, where the game names one, `instructions_per_frame`: the game's own).

    Raises:
        TypeError: an unknown option (the message lists the valid ones).
        ValueError: an option out of range (the message says what it must be).
    """
    check_option_names(options)
    given = {name: value for name, value in options.items() if value is not None}
    defaults = {"freeze_timers": spec.freeze_timers, "max_episode_steps": spec.max_episode_steps}
    if spec.instructions_per_frame is not None:
        defaults["instructions_per_frame"] = spec.instructions_per_frame
    values = {**defaults, **given}
    config = _build(EnvConfig, values)
    if config.mirror and (spec.seats is None or spec.seats.mirror is None):
        raise ValueError(f"{spec.id} has no mirrored seats (Seats.mirror): mirror=True is for "
                         f"{', '.join(mirrored_games())}")
    return config, _build(EnvParams, values)


def mirrored_games() -> list[str]:
    """The two-player games whose seats mirror each other (`Seats.mirror`): those `mirror=True` takes."""
    return [game for game in list_games(players=2) if get_spec(game).seats.mirror is not None]


def make_params(spec: GameSpec, **options: Any) -> EnvParams:
    """The checked `EnvParams` alone (only `EnvParams` fields may be given)."""
    check_option_names(options, PARAM_OPTIONS, "make_params")
    return make_config(spec, **options)[1]


def _build(cls, values: dict[str, Any]):
    """An instance of `cls` from `values` (a field's default where absent), each checked."""
    checked = {}
    for field in dataclasses.fields(cls):
        value = values.get(field.name, field.default)
        checked[field.name] = field.metadata["check"](field.name, value)
        if field.metadata["dtype"] is not None:
            checked[field.name] = jnp.asarray(checked[field.name], field.metadata["dtype"])
    return cls(**checked)
