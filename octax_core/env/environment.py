"""The functional env API (Gymnax-style) over a `GameSpec`: one reset, one step, one autoreset.

    env, params = octax_core.make("Pong")
    obs, state = env.reset(key, params)
    obs, state, reward, terminated, truncated, info = env.step(key, state, action, params)

Two layers, as in gymnax: `reset_env` and `step_env` are the pure game (an ended episode stands
still), and `reset` / `step` add what a training loop needs, the same-step autoreset when the
env is made with `autoreset=True`. `autoreset` is the one reset-where-ended every layer uses:
`step` here, the Gymnasium vector env's NEXT_STEP and SAME_STEP modes and its masked reset,
and the register tracer. Everything is for one env; batch with `jax.vmap` (params broadcast:
`in_axes=(0, 0, 0, None)`) and use inside `jit` and `lax.scan`.

Options that change the traced program are fixed at `make` (`EnvConfig`); `EnvParams` holds what
may change without recompiling (see `octax_core.env.config`). The ROM is booted, its start-up run
and the no-op starts made once, at `make` (`octax_core.env.starts`): a reset draws a start state
and gives it a fresh random seed, at the same small cost whatever `noop_max` is.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, Optional, Union

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.gate import when_any
from octax_core.emulator.machine import Machine
from octax_core.emulator.state import (MachineState, screen_values, shown, screen_values_max, screen_values_shape,
                                       unpack_screen)
from octax_core.env import starts
from octax_core.env.config import EnvConfig, EnvParams, make_config, make_params
from octax_core.env.games import GameSpec, get_spec


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class EnvState:
    """One env: the machine plus the episode bookkeeping."""

    machine: MachineState
    score: jax.Array  # () float32, score_fn at the last step
    episode_step: jax.Array  # () int32
    last_action: jax.Array  # () int32, repeated by sticky actions
    done: jax.Array  # () bool, the episode has ended; further steps change nothing
    game: Optional[jax.Array] = None  # () int32, which game of a mix this env plays (`MixEnv`); else None

    def replace(self, **changes) -> "EnvState":
        return dataclasses.replace(self, **changes)


class Env:
    """A CHIP-8, SUPER-CHIP or XO-CHIP game as a pure, single-env RL environment.

    Observation: uint8 (frames_per_step, 32, 64) on CHIP-8, (frames_per_step, 64, 128) on
    SUPER-CHIP and XO-CHIP whatever mode the program is in (a lores pixel is a 2x2 block), the
    screen after each frame of the step; lit pixels 1 (or 255 with obs_scale=255), and on XO-CHIP
    one value per plane combination (`octax_core.emulator.state.screen_values`: 0..3, or 0, 85,
    170, 255; `observation_high` is the largest). Action: int in 0..num_actions-1; 0 holds no key and
    action i holds `spec.action_keys[i - 1]` for the whole step. Reward: change of the game's
    score over the step, float32, plus `spec.survival_reward` for a step the game goes on after
    (a game with no score of its own). Termination: the spec's `terminated_fn`; truncation after
    `params.max_episode_steps` steps. `info`: score, lives (-1 where the game keeps none),
    episode_step, and with autoreset the final observation and info of an episode that just ended.
    """

    def __init__(self, spec: GameSpec, config: EnvConfig, rom_path=None):
        from octax_core.env.romstore import load_game_rom  # the store does file I/O: only at make

        if config.mirror:  # MultiEnv takes it (make_multi); a one-player env has no second seat
            raise ValueError(f"mirror=True is an option of the two-player env: octax_core.make_multi({spec.id!r}, "
                             "mirror=True)")
        self.spec, self.config = spec, config
        self.machine = Machine(spec.platform, quirks=spec.quirks, instructions_per_frame=config.instructions_per_frame,
                               skip_idle=config.skip_idle)
        template = starts.boot(self.machine, load_game_rom(spec, rom_path), spec.startup)
        noop_step = _noop_stepper(self.machine, config.frames_per_step, config.freeze_timers)
        self._starts = starts.noop_pool(template, noop_step, config.noop_max)
        self._action_masks = np.array([0] + [1 << k for k in spec.action_keys], np.uint32)

    @property
    def num_actions(self) -> int:
        return len(self._action_masks)

    @property
    def name(self) -> str:
        """What this env's errors call it: its game's id."""
        return self.spec.id

    @property
    def observation_shape(self) -> tuple[int, int, int]:
        return (self.config.frames_per_step, *screen_values_shape(self.machine.platform))

    @property
    def observation_high(self) -> int:
        """The largest observed pixel value: obs_scale, or 3 on XO-CHIP with obs_scale=1."""
        return screen_values_max(self.machine.platform, self.config.obs_scale)

    @property
    def default_params(self) -> EnvParams:
        return make_params(self.spec)

    @property
    def compiler_options(self) -> dict[str, object]:
        """Pass to `jax.jit(..., compiler_options=env.compiler_options)` around this env's step:
        its platform's measured XLA settings (`Platform.compiler_options`); same results, faster."""
        return self.machine.compiler_options

    # --- the pure game ------------------------------------------------------------------------

    def reset_env(self, key: jax.Array, params: EnvParams) -> tuple[jax.Array, EnvState]:
        """A new episode: a start state drawn with `key`, which also seeds CXNN.

        The observation repeats the start screen in every frame.
        """
        return self._begin(starts.draw(self._starts, key), None)

    def _begin(self, machine: MachineState, game) -> tuple[jax.Array, EnvState]:
        """The first observation and state of an episode that starts from `machine`."""
        state = EnvState(machine=machine, score=self._score(machine, game), episode_step=jnp.int32(0),
                         last_action=jnp.zeros(self._action_shape, jnp.int32), done=jnp.bool_(False), game=game)
        screens = jnp.broadcast_to(shown(machine)[None], (self.config.frames_per_step, *shown(machine).shape))
        return self._observe(screens), state

    def step_env(self, key: jax.Array, state: EnvState, action, params: EnvParams):
        """Holds the action's key for `frames_per_step` frames; `key` draws the sticky action.

        Returns:
            obs, state, reward, terminated, truncated, info. Once an episode has ended, further
            steps return the same state, zero reward and the same flags.
        """
        return self._transition(key, state, self._check_action(action), params)

    def _transition(self, key: jax.Array, state: EnvState, action: jax.Array, params: EnvParams):
        """`step_env` after the action is checked: one env (`action` ()) or one per seat (`MultiEnv`)."""
        game = state.game  # None but in a mix, where each hook reads its game's own
        repeat = jax.random.uniform(key, jnp.shape(action)) < params.repeat_action_probability
        action = jnp.where(repeat, state.last_action, action)
        # pgx's rule: an ended episode stands still until it is reset. The machine is halted
        # rather than stepped and then discarded, so its 4 KB of memory is never selected over,
        # and the frames it returns are its last screen.
        machine, screens = self._play(state.machine, self._keys_held(action, game), state.done, game)
        score = self._score(machine, game)
        terminated = jnp.asarray(self._terminated(machine, game), jnp.bool_)
        if machine.extension is not None:  # 00FD: the program has ended, so has the episode
            terminated = terminated | machine.extension.exited
        episode_step = jnp.where(state.done, state.episode_step, state.episode_step + 1)
        truncated = ~terminated & (episode_step >= self._max_episode_steps(params, game))
        reward = jnp.where(state.done, 0.0, score - state.score).astype(jnp.float32)
        survival = self._survival_reward(game)
        if survival is not None:  # a game with no score of its own: a reward per step survived
            reward = reward + jnp.where(state.done | terminated, 0.0, survival).astype(jnp.float32)
        new_state = EnvState(machine=machine, score=score, episode_step=episode_step,
                             last_action=jnp.where(state.done, state.last_action, action),
                             done=terminated | truncated, game=game)
        return self._observe(screens), new_state, reward, terminated, truncated, self.info(new_state)

    # --- what a training loop adds ------------------------------------------------------------

    def reset(self, key: jax.Array, params: EnvParams) -> tuple[jax.Array, EnvState]:
        """A new episode (`reset_env`)."""
        return self.reset_env(key, params)

    def step(self, key: jax.Array, state: EnvState, action, params: EnvParams):
        """`step_env`, then, with `config.autoreset`, a new episode where this one ended.

        With autoreset, an ending step returns the new episode's first observation and state;
        `info` keeps the ended episode's score, lives and episode_step, and adds
        `final_observation`, `final_info` and `_final` (true on that step).
        """
        step_key, reset_key = jax.random.split(key)
        obs, state, reward, terminated, truncated, info = self.step_env(step_key, state, action, params)
        if self.config.autoreset:
            info = {**info, "final_observation": obs, "final_info": dict(info), "_final": state.done}
            obs, state = self.autoreset(reset_key, state.done, obs, state, params)
        return obs, state, reward, terminated, truncated, info

    def autoreset(self, key: jax.Array, mask, obs: jax.Array, state: EnvState, params: EnvParams):
        """Where `mask` (bool scalar) holds, a new episode (`reset_env(key)`); else `obs`, `state`.

        Under `vmap` there is no real branching: a new episode is drawn for every env and
        selected where its episode ended, a draw from the start pool and a select over the whole
        state and observation, whatever `noop_max` is. So it runs under `gate.when_any`: on a
        step where no env of the batch ended (most steps: episodes last hundreds of steps) none of
        it runs, and where `mask` is false the select gives `obs` and `state` back bit for bit.
        """
        return when_any(mask, self._restart_where, (obs, state), (key, mask, params))

    def _restart_where(self, operands, inputs):
        """`autoreset`'s work for one env: a new episode, selected where `mask` holds."""
        (obs, state), (key, mask, params) = operands, inputs
        fresh = self.reset_env(key, params)
        return jax.tree.map(lambda new, old: jnp.where(mask, new, old), fresh, (obs, state))

    def info(self, state: EnvState) -> dict[str, jax.Array]:
        """The per-step info of one env: score, lives (-1 where the game keeps none), episode_step."""
        return {"score": state.score, "lives": self._lives(state.machine, state.game),
                "episode_step": state.episode_step}

    # --- pieces (`MultiEnv` replaces those that differ for two seats, `MixEnv` those that differ
    # per game; `game` is the env's game in a mix, None otherwise) ------------------------------

    _action_shape: tuple[int, ...] = ()  # one action a step

    def _keys_held(self, action: jax.Array, game) -> jax.Array:
        """The keypad mask the action holds."""
        return jnp.asarray(self._action_masks)[action]

    def _play(self, machine: MachineState, keys, halted, game):
        """The machine's part of a step: the frames, recorded (`_play` below)."""
        return _play(self.machine, self.config.frames_per_step, self.config.freeze_timers, machine, keys, halted)

    def _terminated(self, machine: MachineState, game) -> jax.Array:
        return self.spec.terminated_fn(machine)

    def _max_episode_steps(self, params: EnvParams, game) -> jax.Array:
        return params.max_episode_steps

    def _survival_reward(self, game):
        """The reward per step survived, or None for a game that keeps a score (nothing traced)."""
        return self.spec.survival_reward or None

    def _observe(self, screens) -> jax.Array:
        if not self.machine.platform.extended:
            return unpack_screen(screens, on=self.config.obs_scale, dtype=jnp.uint8)
        return screen_values(screens, self.machine.platform, on=self.config.obs_scale)

    def _score(self, machine: MachineState, game) -> jax.Array:
        return jnp.asarray(self.spec.score_fn(machine), jnp.float32)

    def _lives(self, machine: MachineState, game) -> jax.Array:
        if self.spec.lives_fn is None:
            return jnp.int32(-1)
        return jnp.asarray(self.spec.lives_fn(machine), jnp.int32)

    def _check_action(self, action) -> jax.Array:
        """The step's action(s), of shape `_action_shape` (one per seat in a `MultiEnv`), as int32.

        The one action check of the core, for every env kind. A concrete action is checked here:
        TypeError for a wrong shape or a non-integer dtype, ValueError naming the first value
        outside 0..num_actions-1. A traced one is checked for shape and dtype (static), not for
        values: under `jit` nothing can be raised, so an out-of-range value holds no key (no-op);
        octax_gym checks every action before or inside its jitted step and raises. The range is
        tested in the action's own dtype and only then narrowed: narrowing first would wrap a wide
        value (int64 2**32 + 1 under `jax_enable_x64`) onto a valid action (1).
        """
        traced = isinstance(action, jax.core.Tracer)
        value = action if traced else np.asarray(action)
        if value.shape != self._action_shape or not jnp.issubdtype(value.dtype, jnp.integer):
            raise TypeError(f"{self.name}: {self._action_form()}; got {value.dtype} of shape {value.shape}")
        if not traced:
            bad = np.argwhere((value < 0) | (value >= self.num_actions))
            if len(bad):
                where = tuple(bad[0])
                seat = f" of seat {self.agents[where[0]]}" if where else ""
                raise ValueError(f"{self.name}: action {int(value[where])}{seat} is out of range; valid actions are "
                                 f"0..{self.num_actions - 1} (0 = no-op)")
        action = jnp.asarray(action)
        return jnp.where((action >= 0) & (action < self.num_actions), action, 0).astype(jnp.int32)

    def _action_form(self) -> str:
        """What a step takes, for `_check_action`'s TypeError (only a `MultiEnv` has seats)."""
        if not self._action_shape:
            return f"an action is one integer in 0..{self.num_actions - 1}"
        return (f"actions are {self._action_shape[0]} integers, one per seat ({', '.join(self.agents)}), "
                f"each in 0..{self.num_actions - 1}")


def _play(machine: Machine, frames_per_step: int, freeze_timers: bool, state: MachineState, keys, halted=None,
          profile=None):
    """The machine's part of an env step: the frames, recorded, then the timers frozen if asked
    (`profile`: the game's, on a mix's machine)."""
    state, screens = machine.run_frames(state, keys, frames_per_step, halted=halted, record_screens=True,
                                        profile=profile)
    if freeze_timers:
        state = state.replace(delay_timer=jnp.zeros_like(state.delay_timer),
                              sound_timer=jnp.zeros_like(state.sound_timer))
    return state, screens


@functools.lru_cache(maxsize=None)
def _noop_stepper(machine: Machine, frames_per_step: int, freeze_timers: bool):
    """One no-op env step for a batch of machines, jitted once per (machine, step) config."""
    return jax.jit(jax.vmap(lambda state: _play(machine, frames_per_step, freeze_timers, state, 0)[0]),
                   compiler_options=machine.compiler_options)


def make(game: Union[str, GameSpec], *, rom=None, **options: Any) -> tuple[Env, EnvParams]:
    """Builds the env for a registered game id (or your own `GameSpec`) and its params.

    Args:
        game: an id from `list_games()`, or a `GameSpec`.
        rom: an explicit ROM path (its SHA-1 must match the spec's).
        **options: `EnvConfig` and `EnvParams` fields (`octax_core.env.config.ENV_OPTIONS`:
            frames_per_step, instructions_per_frame, obs_scale, freeze_timers, noop_max,
            autoreset, skip_idle, max_episode_steps, repeat_action_probability).

    Raises:
        KeyError: unknown game id (the message lists the valid ids).
        TypeError: an unknown option (the message lists the valid ones).
        ValueError: an option out of range.

    >>> env, params = make("Pong")                                   # doctest: +SKIP
    >>> obs, state = env.reset(jax.random.key(0), params)            # doctest: +SKIP
    """
    spec = game if isinstance(game, GameSpec) else get_spec(game)
    if not spec.solo:
        raise ValueError(f"{spec.id} is played by two (its second player must move for the game to go on): "
                         f"use octax_core.make_multi({spec.id!r}), or a fixed opponent in the Gymnasium layer")
    config, params = make_config(spec, **options)
    return Env(spec, config, rom), params
