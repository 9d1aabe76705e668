"""The functional, batched env API (Gymnax-style) over a `GameSpec`.

    env, params = octax_core.make("Pong")
    obs, state = env.reset(key, params)
    obs, state, reward, terminated, truncated, info = env.step(key, state, action, params)

Both functions are for one env; batch them with `jax.vmap` (params broadcast: `in_axes=(0, 0, 0,
None)`), and use them inside `jit` and `lax.scan`. Config that changes the traced program (frames
per step, observation scale, timers, autoreset) is fixed at `make`; `EnvParams` holds what may
change without recompiling. The ROM is booted and its start-up run once, at `make`: a reset
copies that template and swaps in a fresh random state.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, Optional, Union

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator import cpu
from octax_core.env.games import GameSpec, get_spec
from octax_core.emulator.keypad import keys_to_mask
from octax_core.emulator.machine import Machine
from octax_core.emulator.state import MachineState, seed_rng, unpack_screen


@dataclasses.dataclass(frozen=True)
class EnvConfig:
    """What `make` fixes for the compiled program.

    Attributes:
        frames_per_step: 60 Hz frames per env step; the observation holds each of them.
        instructions_per_frame: CHIP-8 instructions per frame.
        obs_scale: lit pixels read 1 (default) or 255.
        freeze_timers: zero both timers after each step (the octax package's `disable_delay`).
        autoreset: reset inside `step` when an episode ends (same-step), for scan loops.
    """

    frames_per_step: int = 4
    instructions_per_frame: int = 11
    obs_scale: int = 1
    freeze_timers: bool = False
    autoreset: bool = False


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class EnvParams:
    """Tunables that may change between calls without recompiling (or be vmapped)."""

    max_episode_steps: jax.Array  # () int32, truncation bound in env steps
    repeat_action_probability: jax.Array  # () float32, sticky actions (Machado et al., 2018)
    noop_max: jax.Array  # () int32, reset runs 0..noop_max no-op steps


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class EnvState:
    """One env: the machine plus the episode bookkeeping."""

    machine: MachineState
    score: jax.Array  # () float32, score_fn at the last step
    episode_step: jax.Array  # () int32
    last_action: jax.Array  # () int32, repeated by sticky actions
    done: jax.Array  # () bool, the episode has ended; further steps change nothing

    def replace(self, **changes) -> "EnvState":
        return dataclasses.replace(self, **changes)


class Env:
    """A CHIP-8 game as a pure, single-env RL environment.

    Observation: uint8 (frames_per_step, 32, 64), the screen after each frame of the step, lit
    pixels 1 (or 255 with obs_scale=255). Action: int in 0..num_actions-1; 0 holds no key and
    action i holds `spec.action_keys[i - 1]` for the whole step. Reward: change of the game's
    score over the step, float32. Termination: the spec's `terminated_fn`; truncation after
    `params.max_episode_steps` steps. `info`: score, lives (-1 where the game keeps none),
    episode_step, and with autoreset the final observation of an episode that just ended.
    """

    def __init__(self, spec: GameSpec, config: EnvConfig, rom_path=None):
        from octax_core.env.romstore import load_game_rom  # the store does file I/O: only at make

        self.spec, self.config = spec, config
        self.machine = Machine(quirks=spec.quirks, instructions_per_frame=config.instructions_per_frame)
        rom = load_game_rom(spec, rom_path)
        self._template = _run_startup(self.machine, rom, spec.startup)
        self._action_masks = np.array([0] + [1 << k for k in spec.action_keys], np.uint32)

    @property
    def num_actions(self) -> int:
        return len(self._action_masks)

    @property
    def observation_shape(self) -> tuple[int, int, int]:
        return (self.config.frames_per_step, 32, 64)

    @property
    def default_params(self) -> EnvParams:
        return make_params(self.spec)

    def reset(self, key: jax.Array, params: EnvParams) -> tuple[jax.Array, EnvState]:
        """A new episode from the start-up template; `key` seeds CXNN and the no-op count."""
        rng_key, noop_key = jax.random.split(key)
        template = jax.tree.map(jnp.asarray, self._template)
        machine = template.replace(rng=seed_rng(rng_key))
        noops = jax.random.randint(noop_key, (), 0, params.noop_max + 1)
        run_step = functools.partial(self._run_step, keys=jnp.uint32(0))
        machine = jax.lax.fori_loop(0, noops, lambda _, m: run_step(m)[0], machine)
        state = EnvState(
            machine=machine,
            score=self._score(machine),
            episode_step=jnp.int32(0),
            last_action=jnp.int32(0),
            done=jnp.bool_(False),
        )
        obs = jnp.broadcast_to(self._pixels(machine.screen[None]), self.observation_shape)
        return obs, state

    def step(self, key: jax.Array, state: EnvState, action, params: EnvParams):
        """Holds the action's key for `frames_per_step` frames.

        Returns:
            obs, state, reward, terminated, truncated, info. Once an episode has ended (without
            autoreset), further steps return the same state, zero reward and the same flags.
        """
        sticky_key, reset_key = jax.random.split(key)
        action = self._check_action(action)
        repeat = jax.random.uniform(sticky_key) < params.repeat_action_probability
        action = jnp.where(repeat, state.last_action, action)
        # pgx's rule: an ended episode stands still until it is reset. The machine is halted
        # rather than stepped and then discarded, so its 4 KB of memory is never selected over,
        # and the frames it returns are its last screen.
        machine, screens = self._run_step(state.machine, jnp.asarray(self._action_masks)[action],
                                          halted=state.done)
        score = self._score(machine)
        terminated = jnp.asarray(self.spec.terminated_fn(machine), jnp.bool_)
        episode_step = jnp.where(state.done, state.episode_step, state.episode_step + 1)
        truncated = ~terminated & (episode_step >= params.max_episode_steps)
        reward = jnp.where(state.done, 0.0, score - state.score).astype(jnp.float32)
        new_state = EnvState(
            machine=machine,
            score=score,
            episode_step=episode_step,
            last_action=jnp.where(state.done, state.last_action, action),
            done=terminated | truncated,
        )
        obs = self._pixels(screens)
        info = self.info(new_state)
        if self.config.autoreset:
            obs, new_state, info = self._autoreset(reset_key, obs, new_state, info, params)
        return obs, new_state, reward, terminated, truncated, info

    def info(self, state: EnvState) -> dict[str, jax.Array]:
        """The per-step info of one env: score, lives (-1 where the game keeps none), episode_step."""
        return {"score": state.score, "lives": self._lives(state.machine), "episode_step": state.episode_step}

    # --- pieces -------------------------------------------------------------------------------

    def _run_step(self, machine: MachineState, keys, halted=None) -> tuple[MachineState, jax.Array]:
        """frames_per_step frames with `keys` held; returns the packed screen after each."""
        def frame(machine, _):
            machine = cpu.run_frame(self.machine.quirks, self.config.instructions_per_frame, machine,
                                    keys, halted)
            return machine, machine.screen

        machine, screens = jax.lax.scan(frame, machine, None, length=self.config.frames_per_step)
        if self.config.freeze_timers:
            machine = machine.replace(delay_timer=jnp.zeros_like(machine.delay_timer),
                                      sound_timer=jnp.zeros_like(machine.sound_timer))
        return machine, screens

    def _pixels(self, screens) -> jax.Array:
        return unpack_screen(screens, on=self.config.obs_scale, dtype=jnp.uint8)

    def _score(self, machine: MachineState) -> jax.Array:
        return jnp.asarray(self.spec.score_fn(machine), jnp.float32)

    def _lives(self, machine: MachineState) -> jax.Array:
        if self.spec.lives_fn is None:
            return jnp.int32(-1)
        return jnp.asarray(self.spec.lives_fn(machine), jnp.int32)

    def _autoreset(self, key, obs, state: EnvState, info: dict, params: EnvParams):
        reset_obs, reset_state = self.reset(key, params)
        ended = state.done
        info = {**info, "final_observation": obs, "final_info": dict(info), "_final": ended}
        state = jax.tree.map(lambda fresh, old: jnp.where(ended, fresh, old), reset_state, state)
        return jnp.where(ended, reset_obs, obs), state, info

    def _check_action(self, action) -> jax.Array:
        if not isinstance(action, jax.core.Tracer):
            value = np.asarray(action)
            if value.shape != () or not np.issubdtype(value.dtype, np.integer):
                raise TypeError(f"{self.spec.id}: an action is one integer, got {value.dtype} of shape {value.shape}")
            if not 0 <= int(value) < self.num_actions:
                raise ValueError(f"{self.spec.id}: action {int(value)} is out of range; valid actions are "
                                 f"0..{self.num_actions - 1} (0 = no-op, keys {list(self.spec.action_keys)})")
        # Traced actions cannot be checked here: out-of-range values hold no key (documented);
        # octax_gym checks every action on the host before it reaches the device.
        action = jnp.asarray(action, jnp.int32)
        return jnp.where((action >= 0) & (action < self.num_actions), action, 0)



@functools.lru_cache(maxsize=None)
def _frames_runner(machine: Machine):
    """Runs a traced number of frames with a held key mask; compiled once per machine."""
    def run(state, keys, frames):
        frame = lambda _, s: cpu.run_frame(machine.quirks, machine.instructions_per_frame, s, keys)
        return jax.lax.fori_loop(0, frames, frame, state)
    return jax.jit(run)


def _run_startup(machine: Machine, rom, startup) -> MachineState:
    """Boots `rom` and runs the start-up (key mask, frames) steps; host numpy arrays out."""
    state = machine.boot(rom, jax.random.key(0))
    run = _frames_runner(machine)
    for mask, frames in startup:
        state = run(state, keys_to_mask(mask), frames)
    return jax.tree.map(np.asarray, state)


def make_params(spec: GameSpec, max_episode_steps: Optional[int] = None,
                repeat_action_probability: float = 0.0, noop_max: int = 0) -> EnvParams:
    """`EnvParams` with checked values; the spec gives the default episode bound."""
    steps = spec.max_episode_steps if max_episode_steps is None else max_episode_steps
    if isinstance(steps, bool) or not isinstance(steps, int) or steps <= 0:
        raise ValueError(f"max_episode_steps must be a positive int, got {steps!r}")
    if not 0.0 <= float(repeat_action_probability) <= 1.0:
        raise ValueError(f"repeat_action_probability must be in [0, 1], got {repeat_action_probability!r}")
    if isinstance(noop_max, bool) or not isinstance(noop_max, int) or noop_max < 0:
        raise ValueError(f"noop_max must be an int >= 0, got {noop_max!r}")
    return EnvParams(jnp.int32(steps), jnp.float32(repeat_action_probability), jnp.int32(noop_max))


_CONFIG_FIELDS = {f.name for f in dataclasses.fields(EnvConfig)}
_PARAM_FIELDS = {"max_episode_steps", "repeat_action_probability", "noop_max"}


def make(game: Union[str, GameSpec], *, rom=None, **overrides: Any) -> tuple[Env, EnvParams]:
    """Builds the env for a registered game id (or your own `GameSpec`) and its default params.

    Args:
        game: an id from `list_games()`, or a `GameSpec`.
        rom: an explicit ROM path (its SHA-1 must match the spec's).
        **overrides: `EnvConfig` fields (frames_per_step, instructions_per_frame, obs_scale,
            freeze_timers, autoreset) and `EnvParams` fields (max_episode_steps,
            repeat_action_probability, noop_max).

    Raises:
        KeyError: unknown game id (the message lists the valid ids).
        TypeError: an unknown override (the message lists the valid ones).
        ValueError: an override out of range.

    >>> env, params = make("Pong")                                   # doctest: +SKIP
    >>> obs, state = env.reset(jax.random.key(0), params)            # doctest: +SKIP
    """
    spec = game if isinstance(game, GameSpec) else get_spec(game)
    config, params = make_config(spec, **overrides)
    return Env(spec, config, rom), params


def make_config(spec: GameSpec, **overrides: Any) -> tuple[EnvConfig, EnvParams]:
    """The checked `EnvConfig` and `EnvParams` that `make` would use, without booting the ROM.

    Raises:
        TypeError: an unknown override (the message lists the valid ones).
        ValueError: an override out of range.
    """
    unknown = set(overrides) - _CONFIG_FIELDS - _PARAM_FIELDS
    if unknown:
        raise TypeError(f"unknown override(s) {sorted(unknown)}; valid: {sorted(_CONFIG_FIELDS | _PARAM_FIELDS)}")
    config_args = {k: v for k, v in overrides.items() if k in _CONFIG_FIELDS}
    if config_args.get("freeze_timers") is None:
        config_args["freeze_timers"] = spec.freeze_timers
    config = EnvConfig(**config_args)
    _check_config(config)
    params = make_params(spec, **{k: v for k, v in overrides.items() if k in _PARAM_FIELDS})
    return config, params


def _check_config(config: EnvConfig) -> None:
    for name in ("frames_per_step", "instructions_per_frame"):
        value = getattr(config, name)
        if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
            raise ValueError(f"{name} must be a positive int, got {value!r}")
    if config.obs_scale not in (1, 255):
        raise ValueError(f"obs_scale must be 1 (pixels 0/1) or 255 (pixels 0/255), got {config.obs_scale!r}")
    for name in ("freeze_timers", "autoreset"):
        if not isinstance(getattr(config, name), bool):
            raise ValueError(f"{name} must be True or False, got {getattr(config, name)!r}")
