"""Many games in one batch: one jitted program, a different game in every env (a mix).

    env, params = octax_core.make_mix(["Pong", "Brix", "Tetris"])
    obs, state = env.reset(key, params)             # draws the env's game (uniform, or `weights`)
    obs, state = env.reset(key, params, game=1)     # or forces it (an int, or a traced int32)
    obs, state, reward, terminated, truncated, info = env.step(key, state, action, params)
    info["game"], info["action_mask"]               # which game, and the actions it takes

The game is data. Each env's ROM is in its machine's memory, so a game is the start states the
env resets to plus a few things looked up by its game index (`EnvState.game`): its quirks and
speed (the machine's `profiles`: quirks the games share stay constants of the traced program,
the others are read per machine, and each machine keeps its own frame clock, so a 15-instruction
game and an 11-instruction one step together), its keys, whether its timers are frozen, its
episode length, and its score, lives and end (`lax.switch` on the game's function: under `vmap`
every distinct function runs on every machine and the env's own is selected; they read a few
registers, and games sharing a function share its branch).

`MixEnv` is `Env` with those pieces per game (`Env._transition`, `Env.autoreset`: one step, one
autoreset), so an env reset with `game=i` plays, step for step, exactly what `make(games[i])`
plays from the same keys and actions: observations, rewards, flags and info. Autoreset starts
the next episode on a game drawn from `weights` again.

The action space is the largest game's: action `a` of an env is its game's own action `a`
(0 = no-op), and an action past its game's last holds no key (`info["action_mask"]` marks the
actions each env's game takes, for a masked policy; an unmasked one, SB3's PPO say, just wastes
those actions, as it would a no-op). One platform per mix:
CHIP-8 games together, SUPER-CHIP games together, XO-CHIP games together (the machine's memory
and screen are the platform's).
"""

from __future__ import annotations

import dataclasses
from typing import Any, Optional, Sequence, Union

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.machine import Machine
from octax_core.emulator.state import MachineState
from octax_core.env import starts
from octax_core.env.config import EnvParams, make_config
from octax_core.env.environment import Env, EnvState, _noop_stepper, _play
from octax_core.env.games import GameSpec, get_spec, list_games

GAME_STREAM = 0x6A4D  # folded into a reset's key to draw the game, so the start draw is make()'s

# Named mixes. octax16: sixteen of the octax paper's titles, as many as its training figure
# has: the ten its text discusses (Airplane, Blinky, Brix, Deep8, Filter, Pong, Tank, Tetris,
# VerticalBrix, Worm) and the other six single-level titles that are not exploration games.
MIXES: dict[str, tuple[str, ...]] = {
    "octax16": ("Airplane", "Blinky", "Brix", "Deep8", "Filter", "Missile", "Pong", "Rocket", "ShootingStars",
                "Squash", "Submarine", "Tank", "Tetris", "UFO", "VerticalBrix", "Worm"),
}


class MixEnv(Env):
    """Envs that each play one of `specs`, stepped as one program. See the module docstring."""

    def __init__(self, specs: Sequence[GameSpec], weights: Optional[Sequence[float]], options: dict,
                 roms: Optional[Sequence] = None):
        from octax_core.env.romstore import load_game_rom  # the store does file I/O: only at make

        _check_specs(specs, roms)
        self.specs = tuple(specs)
        self.spec = self.specs[0]
        self.weights = _check_weights(weights, len(self.specs))
        configs, params = zip(*(make_config(spec, **options) for spec in self.specs))
        if configs[0].mirror:
            raise ValueError("mirror=True is an option of the two-player env (octax_core.make_multi); a mix is one-player")
        self.configs = configs
        platform = self.specs[0].platform
        self.machine = Machine(platform, skip_idle=configs[0].skip_idle,
                               profiles=tuple((spec.quirks, config.instructions_per_frame)
                                              for spec, config in zip(self.specs, configs)))
        self.config = dataclasses.replace(configs[0], instructions_per_frame=self.machine.instructions_per_frame,
                                          freeze_timers=any(config.freeze_timers for config in configs))
        self._params = EnvParams(max_episode_steps=jnp.stack([p.max_episode_steps for p in params]),
                                 repeat_action_probability=params[0].repeat_action_probability)
        pools = []
        for index, (spec, config) in enumerate(zip(self.specs, configs)):
            # Each game's starts are made by the game's own machine, exactly as `make` makes them.
            own = Machine(platform, quirks=spec.quirks, instructions_per_frame=config.instructions_per_frame,
                          skip_idle=config.skip_idle)
            template = starts.boot(own, load_game_rom(spec, None if roms is None else roms[index]), spec.startup)
            noop_step = _noop_stepper(own, config.frames_per_step, config.freeze_timers)
            pools.append(starts.noop_pool(template, noop_step, config.noop_max))
        self._starts = jax.tree.map(lambda *leaves: np.stack(leaves), *pools)
        actions = max(len(spec.action_keys) for spec in self.specs) + 1
        self._game_masks = np.zeros((len(self.specs), actions), np.uint32)
        for index, spec in enumerate(self.specs):
            self._game_masks[index, 1:len(spec.action_keys) + 1] = [1 << k for k in spec.action_keys]
        self._legal = np.arange(actions)[None, :] <= np.array([len(s.action_keys) for s in self.specs])[:, None]
        self._action_masks = self._game_masks[0]  # num_actions: the largest game's
        self._freeze = np.array([config.freeze_timers for config in configs])
        self._survival = np.array([spec.survival_reward for spec in self.specs], np.float32)

    @property
    def games(self) -> tuple[str, ...]:
        return tuple(spec.id for spec in self.specs)

    @property
    def num_games(self) -> int:
        return len(self.specs)

    @property
    def name(self) -> str:
        """What this env's errors call it: mix(its games); action i is each game's own action i."""
        return f"mix({', '.join(self.games)})"

    @property
    def default_params(self) -> EnvParams:
        """max_episode_steps per game (each game's own unless `make_mix` was told one for all)."""
        return self._params

    # --- the pure game ------------------------------------------------------------------------

    def reset_env(self, key: jax.Array, params: EnvParams, game=None) -> tuple[jax.Array, EnvState]:
        """A new episode on `game` (an int or an int32 scalar, traced or not), or on a game drawn
        from the weights; the start state is drawn with `key` exactly as `make(game)` draws it."""
        if game is None:
            game = jax.random.choice(jax.random.fold_in(key, GAME_STREAM), self.num_games, p=jnp.asarray(self.weights))
        elif not isinstance(game, jax.core.Tracer) and not 0 <= int(game) < self.num_games:
            raise ValueError(f"game {int(game)} is out of range; this mix's games are 0..{self.num_games - 1}: "
                             + ", ".join(f"{i} {g}" for i, g in enumerate(self.games)))
        game = jnp.asarray(game, jnp.int32)
        pool = jax.tree.map(lambda leaf: jnp.asarray(leaf)[game], self._starts)
        return self._begin(starts.draw(pool, key), game)

    def reset(self, key: jax.Array, params: EnvParams, game=None) -> tuple[jax.Array, EnvState]:
        """A new episode (`reset_env`)."""
        return self.reset_env(key, params, game)

    def action_mask(self, state: EnvState) -> jax.Array:
        """bool (num_actions,): the actions this env's game takes (its keys, and no-op)."""
        return jnp.asarray(self._legal)[state.game]

    def info(self, state: EnvState) -> dict[str, jax.Array]:
        """`Env.info` plus `game` (the index into `games`) and `action_mask`."""
        return {**super().info(state), "game": state.game, "action_mask": self.action_mask(state)}

    # --- pieces, per game ---------------------------------------------------------------------

    def _keys_held(self, action: jax.Array, game) -> jax.Array:
        return jnp.asarray(self._game_masks)[game, action]

    def _play(self, machine: MachineState, keys, halted, game):
        machine, screens = _play(self.machine, self.config.frames_per_step, False, machine, keys, halted, profile=game)
        if self._freeze.any():
            freeze = jnp.asarray(self._freeze)[game]
            machine = machine.replace(delay_timer=jnp.where(freeze, 0, machine.delay_timer).astype(machine.delay_timer.dtype),
                                      sound_timer=jnp.where(freeze, 0, machine.sound_timer).astype(machine.sound_timer.dtype))
        return machine, screens

    def _score(self, machine: MachineState, game) -> jax.Array:
        return self._per_game("score_fn", jnp.float32, 0, machine, game)

    def _terminated(self, machine: MachineState, game) -> jax.Array:
        return self._per_game("terminated_fn", jnp.bool_, False, machine, game)

    def _lives(self, machine: MachineState, game) -> jax.Array:
        return self._per_game("lives_fn", jnp.int32, -1, machine, game)

    def _per_game(self, field: str, dtype, default, machine: MachineState, game) -> jax.Array:
        """The game's `field` function (its score, end or lives) of `machine`: a `lax.switch`
        over the mix's distinct functions, each game mapped to its own by a table. Games that
        share a function (the variants of a generated family: one score function, the ROM is
        data) share a branch, so the program does not grow with the number of games; a game
        without the function (no lives) reads `default`."""
        functions, branch_of = self._distinct_functions(field)
        branches = [(lambda m: jnp.asarray(default, dtype)) if fn is None else
                    (lambda m, fn=fn: jnp.asarray(fn(m), dtype)) for fn in functions]
        return jax.lax.switch(jnp.asarray(branch_of)[game], branches, machine)

    def _distinct_functions(self, field: str) -> tuple[list, np.ndarray]:
        """The distinct `field` functions of the specs, in first-seen order, and each game's index into them."""
        functions: list = []
        branch_of = []
        for spec in self.specs:
            fn = getattr(spec, field)
            index = next((i for i, known in enumerate(functions) if known is fn), None)
            if index is None:
                index = len(functions)
                functions.append(fn)
            branch_of.append(index)
        return functions, np.array(branch_of, np.int32)

    def _max_episode_steps(self, params: EnvParams, game) -> jax.Array:
        return params.max_episode_steps[game]

    def _survival_reward(self, game):
        return jnp.asarray(self._survival)[game] if self._survival.any() else None


def _check_specs(specs: Sequence[GameSpec], roms) -> None:
    """Raises ValueError for a mix that cannot be one program: no games, several platforms, a
    two-player-only game, roms that do not match the games."""
    if not len(specs):
        raise ValueError(f"a mix needs a non-empty list of games or a named mix ({', '.join(MIXES)})")
    platforms = sorted({spec.platform for spec in specs})
    if len(platforms) > 1:
        by_platform = "; ".join(f"{p}: " + ", ".join(s.id for s in specs if s.platform == p) for p in platforms)
        raise ValueError(f"a mix runs games of one platform, got several ({by_platform})")
    if not_solo := [spec.id for spec in specs if not spec.solo]:
        raise ValueError(f"{', '.join(not_solo)}: played by two, not a one-player env; a mix takes one-player games")
    if roms is not None and len(roms) != len(specs):
        raise ValueError(f"roms must be one path (or None) per game ({len(specs)}), got {len(roms)}")


def _check_weights(weights, count: int) -> np.ndarray:
    if weights is None:
        return np.full(count, 1.0 / count, np.float32)
    values = np.asarray(weights, np.float64)
    if values.shape != (count,):
        raise ValueError(f"weights must be one number per game ({count}), got shape {values.shape}")
    if not np.isfinite(values).all() or (values < 0).any() or values.sum() <= 0:
        raise ValueError(f"weights must be finite, >= 0 and not all 0, got {list(weights)}")
    return (values / values.sum()).astype(np.float32)


def make_mix(games: Sequence[Union[str, GameSpec]], weights: Optional[Sequence[float]] = None, *,
             roms: Optional[Sequence] = None, **options: Any) -> tuple[MixEnv, EnvParams]:
    """One env over several games: each env of a batch plays one of `games` (see the module docstring).

    Args:
        games: registered ids (`list_games()`) and/or your own `GameSpec`s, all of one platform;
            or the name of a mix in `MIXES` ("octax16").
        weights: how often a reset draws each game (normalised); uniform by default.
        roms: explicit ROM paths, one per game (None entries: the ROM store's).
        **options: `make`'s options, applied to every game (`ENV_OPTIONS`); one left out takes each
            game's own default (instructions_per_frame, freeze_timers, max_episode_steps).

    Raises:
        ValueError: no games, games of several platforms, a two-player-only game, weights or
            roms that do not match the games. KeyError: an unknown game id (the message lists
            the valid ones). TypeError: an unknown option.
    """
    if isinstance(games, str) and games in MIXES:
        games = MIXES[games]
    if isinstance(games, (str, GameSpec)) or not len(games):
        raise ValueError(f"make_mix needs a non-empty list of games or a named mix ({', '.join(MIXES)}); "
                         f"valid ids: {', '.join(list_games())}")
    specs = [game if isinstance(game, GameSpec) else get_spec(game) for game in games]
    env = MixEnv(specs, weights, options, roms)
    return env, env.default_params
