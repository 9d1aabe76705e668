"""The compiled env step behind the Gymnasium envs: one jitted call per reset and per step.

Both envs (`OctaxEnv`, `OctaxVectorEnv`) run the functional core (`octax_core.make`, its own
autoreset off) through this, and differ only in batching and host conversions. What is here is
what Gymnasium adds to the core:

* every env carries its own PRNG key; each step splits it three ways (next key, step key, reset
  key), so one env's randomness never depends on how many envs run beside it;
* a reset with seed s starts env i's chain at `jax.random.key(s + i)` (Gymnasium's `SyncVectorEnv`
  seeds its sub-envs s, s+1, ...), so row i equals a single env reset with seed s + i;
* Gymnasium's autoreset modes pick which rows the core's one `Env.autoreset` restarts: NEXT_STEP
  the rows that had ended before this step, SAME_STEP the rows that end in it, and a masked
  `reset` the rows asked for;
* the info dict gets Gymnasium's `_name` masks, and SAME_STEP its batched `final_obs`/`final_info`;
* device actions get their range checked in the step (`octax_gym.step.action_check`).

Two-player games run through the same class: built over a `MultiEnv` (`octax_core.make_multi`)
the batch of actions is (N, 2), rewards (N, 2), observations (N, 2, F+1, H, W), and the device
report also catches closed actions (`action_check.accumulate_seats`); that is
`octax_gym.MultiAgentVectorEnv`. Built with a `View` (`octax_gym.step.opponent`) it is one seat against
a fixed opponent: the learner's actions (N,) go in, the opponent's are made inside the step (or
come from the host), and the learner's observation, reward and info come out, so that
`OctaxVectorEnv(game, opponent=...)` is a one-player env to every caller.

A mix of games (`octax_core.make_mix`, `build_mix`) runs through it too: its env is a `MixEnv`,
whose actions past an env's game's last are no-op and whose info adds `game` and `action_mask`.

`CompiledStep`s are cached per (game, config, ROM, players, view), or per (games, weights,
options) for a mix, so every env of one game or mix shares its compilations.
"""

from __future__ import annotations

import functools
from typing import Any, Optional

import jax
import jax.numpy as jnp
import numpy as np
from gymnasium.vector import AutoresetMode

import octax_core
from octax_core.env import ENV_OPTIONS, Env, EnvConfig, EnvParams, EnvState, GameSpec
from octax_core.env.games import list_games
from octax_core.env.mix import MIXES, MixEnv
from octax_core.env.multi import MultiEnv
from octax_gym.envs.game_names import resolve_spec
from octax_gym.step import action_check, opponent

# What the Gymnasium envs pass to the core: every env option but `autoreset`, which Gymnasium's
# own `autoreset_mode` replaces.
GYM_ENV_OPTIONS = tuple(name for name in ENV_OPTIONS if name != "autoreset")


def advance(key: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """One env's key -> (its next key, a key for this step, a key for a reset in this step)."""
    next_key, step_key, reset_key = jax.random.split(key, 3)
    return next_key, step_key, reset_key


class CompiledStep:
    """The jitted reset and step of one game and config, for any batch size.

    `env` is an `Env`, or a `MultiEnv` for two seats; `view` (a `MultiEnv` only) makes it one seat
    against a fixed opponent (see the module docstring).
    """

    def __init__(self, env: Env, view: Optional[opponent.View] = None):
        self.env, self.view = env, view
        self.players = env.players if isinstance(env, MultiEnv) else 1
        if view is None:
            self.info = jax.vmap(env.info)
            self._autoreset = jax.vmap(env.autoreset, in_axes=(0, 0, 0, 0, None))
        else:
            self.info = jax.vmap(lambda state: opponent.learner_info(env.info(state), view.seat))
            self._autoreset = jax.vmap(self._learner_autoreset, in_axes=(0, 0, 0, 0, None))
        # The platform's measured XLA settings (`Platform.compiler_options`). JAX takes compile
        # options on the outermost jit only, so a caller that jits around the step (a dataset
        # collector, a sharded env) calls the unjitted `reset_fn` / `step_fns` and passes them itself.
        self.compiler_options = env.compiler_options
        self.reset_fn = self._reset
        self.step_fns = {mode: functools.partial(self._step, mode=mode) for mode in AutoresetMode}
        self.reset = jax.jit(self.reset_fn, compiler_options=self.compiler_options)
        self.step = {mode: jax.jit(fn, donate_argnums=(1,), compiler_options=self.compiler_options)
                     for mode, fn in self.step_fns.items()}

    # batched: keys (N,), state EnvState with (N, ...) leaves

    def _reset(self, keys, state: Optional[EnvState], obs, mask, params: EnvParams):
        """Resets the rows in `mask` (all rows when `state` is None); returns keys, obs, state, info."""
        next_keys, _, reset_keys = jax.vmap(advance)(keys)
        if state is None:
            obs, state = jax.vmap(self.env.reset, in_axes=(0, None))(reset_keys, params)
            if self.view is not None:
                obs = obs[:, self.view.seat]
        else:
            obs, state = self._autoreset(reset_keys, mask, obs, state, params)
            next_keys = select_keys(mask, next_keys, keys)
        return next_keys, obs, state, self._with_masks(self.info(state))

    def _step(self, keys, state: EnvState, actions, report, params: EnvParams, opponent_actions=None, *,
              mode: AutoresetMode):
        """One batched step; also returns the action report (`octax_gym.step.action_check`) updated
        with this step's actions, as its last output. `opponent_actions` (N,): a host function
        opponent's (a view with opponent "callable" only)."""
        if self.players == 1:
            report = action_check.accumulate(report, actions, self.env.num_actions)
        next_keys, step_keys, reset_keys = jax.vmap(advance)(keys)
        was_done = state.done
        if self.players > 1:
            if self.view is not None:
                actions = opponent.actions_of_both(self.env, self.view, step_keys, state, actions, opponent_actions)
            report = self._accumulate_seats(report, state, actions)
        obs, state, reward, terminated, truncated, info = jax.vmap(
            self.env.step, in_axes=(0, 0, 0, None))(step_keys, state, actions, params)
        if self.view is not None:
            seat = self.view.seat
            obs, reward, info = obs[:, seat], reward[:, seat], opponent.learner_info(info, seat)
        if mode == AutoresetMode.NEXT_STEP:
            # The step after an episode's end is its reset: the action is ignored, and the core
            # already gave the ended (standing-still) row reward 0; its flags are cleared here.
            obs, state = self._autoreset(reset_keys, was_done, obs, state, params)
            terminated, truncated = terminated & ~was_done, truncated & ~was_done
            info = self.info(state)
        elif mode == AutoresetMode.SAME_STEP:
            ended = state.done
            final = {"final_obs": obs, "_final_obs": ended,
                     "final_info": self._with_masks(info), "_final_info": ended}
            obs, state = self._autoreset(reset_keys, ended, obs, state, params)
            info = {**self._with_masks(self.info(state)), **final}
            return next_keys, obs, state, reward, terminated, truncated, info, report
        return next_keys, obs, state, reward, terminated, truncated, self._with_masks(info), report

    def _accumulate_seats(self, report, state: EnvState, actions):
        """The two-seat report: out-of-range actions, and closed ones where an episode is on and
        the seat is not a view's opponent (a closed opponent action is its no-op, not an error)."""
        open_actions = jax.vmap(self.env.legal_action_mask)(state) | state.done[:, None, None]
        if self.view is not None:
            open_actions = open_actions.at[:, self.view.other].set(True)
        mover = jax.vmap(self.env.current_player)(state)
        return action_check.accumulate_seats(report, actions, open_actions, mover, self.env.num_actions)

    def _learner_autoreset(self, key, mask, obs, state: EnvState, params: EnvParams):
        """`Env.autoreset` of one env seen from the view's seat: `obs` is the learner's alone, so
        the other seat's rows are a stand-in that the new episode's replace or that is dropped."""
        seat = self.view.seat
        both = jnp.zeros((self.players, *obs.shape), obs.dtype).at[seat].set(obs)
        both, state = self.env.autoreset(key, mask, both, state, params)
        return both[seat], state

    @staticmethod
    def _with_masks(info: dict) -> dict:
        """Gymnasium's vector-info convention: each key `k` comes with a bool mask `_k`. An
        `action_mask` (a seat's against an opponent, a mix's) leaves as int8, the dtype
        Gymnasium's `Discrete.sample(mask=...)` takes, as PettingZoo's masks are."""
        if "action_mask" in info:
            info = {**info, "action_mask": info["action_mask"].astype(jnp.int8)}
        return {**info, **{f"_{name}": jnp.ones(value.shape[:1], jnp.bool_) for name, value in info.items()}}


def select_keys(mask, on_true, on_false):
    """Row-wise select between two batches of typed PRNG keys."""
    data_true, data_false = jax.random.key_data(on_true), jax.random.key_data(on_false)
    data = jnp.where(mask.reshape(mask.shape + (1,) * (data_true.ndim - 1)), data_true, data_false)
    return jax.random.wrap_key_data(data, impl=jax.random.key_impl(on_true))


@functools.lru_cache(maxsize=64)
def _compiled_step(spec: GameSpec, config: EnvConfig, rom: Optional[str], players: int = 1,
                   view: Optional[opponent.View] = None) -> CompiledStep:
    if players == 1:
        return CompiledStep(Env(spec, config, rom))
    return CompiledStep(MultiEnv(spec, config, rom), view)


@functools.lru_cache(maxsize=16)
def _compiled_mix(specs: tuple[GameSpec, ...], weights: Optional[tuple[float, ...]],
                  options: tuple[tuple[str, Any], ...]) -> CompiledStep:
    return CompiledStep(MixEnv(specs, weights, dict(options)))


def is_mix(game: Any) -> bool:
    """Whether `game` names several games: a list or tuple of games, or a mix in `MIXES`."""
    return isinstance(game, (list, tuple)) or (isinstance(game, str) and game in MIXES)


def build_mix(games: Any, weights, options: dict[str, Any]) -> tuple[CompiledStep, EnvParams]:
    """The cached compiled step of a mix (`octax_core.make_mix`): a list of games (any names
    `resolve_spec` takes, or `GameSpec`s) or a mix's name, `weights` per game (None: uniform)."""
    names = MIXES[games] if isinstance(games, str) else games
    if not len(names):
        raise ValueError(f"a mix needs a non-empty list of games, or one of the named mixes: {', '.join(MIXES)}")
    specs = tuple(resolve_spec(game) for game in names)
    given = tuple(sorted((name, value) for name, value in options.items() if value is not None))
    octax_core.make_config(specs[0], autoreset=False, **options)  # checks every option first
    weights = None if weights is None else tuple(float(w) for w in weights)
    compiled = _compiled_mix(specs, weights, given + (("autoreset", False),))
    return compiled, compiled.env.default_params


def build(game: Any, rom, options: dict[str, Any], *, players: int = 1,
          view: Optional[opponent.View] = None) -> tuple[CompiledStep, EnvParams]:
    """The cached compiled step and checked params for a game (any name `resolve_spec` takes, or a
    `GameSpec`) and `GYM_ENV_OPTIONS` keywords (None means the game's default).

    `players=2` builds the two-player env (`octax_core.make_multi`), seen from one seat against
    an opponent when `view` is given.

    Raises:
        ValueError: `players=2` for a one-player game (the message lists the two-player ones).
    """
    spec = resolve_spec(game, players)
    if players == 2 and spec.seats is None:
        raise ValueError(f"{spec.id} is a one-player game; two-player games: {', '.join(list_games(players=2))}")
    config, params = octax_core.make_config(spec, autoreset=False, **options)  # checks every value
    rom = None if rom is None else str(rom)
    if players == 1:  # the one-player call, as it always was
        return _compiled_step(spec, config, rom), params
    return _compiled_step(spec, config, rom, players, view), params


def seeds_for(seed, num_envs: int) -> list[int]:
    """Per-env seeds as Gymnasium's SyncVectorEnv makes them: an int s gives s, s+1, ...; a list
    gives one per env."""
    def valid(s):
        return isinstance(s, (int, np.integer)) and not isinstance(s, bool) and 0 <= s < MAX_SEED

    if valid(seed) and seed + num_envs <= MAX_SEED:
        return [int(seed) + i for i in range(num_envs)]
    if isinstance(seed, (list, tuple)) and len(seed) == num_envs and all(valid(s) for s in seed):
        return [int(s) for s in seed]
    raise ValueError(f"seed must be None, an int in 0..2**32 - num_envs, or a list of {num_envs} ints in "
                     f"0..2**32 - 1, got {seed!r}")


MAX_SEED = 2**32  # seeds become uint32 JAX PRNG seeds


def keys_from_seeds(seeds: list[int]) -> jax.Array:
    return jax.vmap(jax.random.key)(jnp.asarray(seeds, jnp.uint32))
