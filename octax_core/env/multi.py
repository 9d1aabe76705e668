"""Two players on one machine: the functional multi-agent env (pgx and JaxMARL are the models).

    env, params = octax_core.make_multi("Duel")
    obs, state = env.reset(key, params)                    # obs: (players, planes, H, W)
    obs, state, rewards, terminated, truncated, info = env.step(key, state, actions, params)

`MultiEnv` is the one-player `Env` with one action per seat: the same machine, start pool, frame
loop, sticky actions, truncation and autoreset (`Env._transition`, `Env.autoreset`), with the
pieces that differ for two seats replaced:

- actions: int32 `(players,)`; action 0 of a seat is no-op and action i holds
  `seats.action_keys[seat][i - 1]`. Both seats' keys reach the one keypad in the same step: a key
  held by either is held. With sticky actions each seat repeats its own last action.
- rewards: float32 `(players,)`, the change of each seat's score (`Seats.score_fn`).
  `terminated` and `truncated` are shared: one machine, one episode.
- observations: uint8 `(players, frames_per_step + 1, H, W)`: the screens of the step (the same
  for both seats), then a player plane, 0 everywhere for the first seat and `obs_scale` for the
  second. One screen, two readers: a player plane tells each which side it plays in every game,
  turn-based, simultaneous or XO-CHIP, where a mirrored view would work only for games whose two
  sides are each other's reflection, and would hide a turn-based game's X from its O.
- turn-based games (`Seats.turn_fn`): `info["current_player"]` is the seat to move, and
  `info["legal_action_mask"]` (players, num_actions) opens only no-op to the other seat. Here, in
  the functional core, an action the mask closes is played as no-op (under `jit` nothing can be
  raised); the Gymnasium and PettingZoo layers raise an error for it instead. Simultaneous games
  have `current_player` -1 and every action open to both seats.
- `mirror=True` (games with `Seats.mirror`: `octax_core.env.config.mirrored_games()`): seat 1
  sees the screens flipped across the game's axis (its player plane as before) and plays its
  actions through `Seats.mirror_actions`, both in its observation and in its legal mask, so
  one network plays either seat as seat 0 and still knows which by the plane. The machine,
  `last_action` (sticky actions) and the scores stay the game's own. A scripted player
  (`Seats.scripted_policy`) gives the game's own action: map seat 1's with `mirror_action`.

Everything is for one env: batch with `jax.vmap` (`in_axes=(0, 0, 0, None)`), as for `Env`.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Union

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.state import MachineState
from octax_core.env.config import make_config
from octax_core.env.environment import Env, EnvParams, EnvState
from octax_core.env.games import GameSpec, get_spec, list_games


class MultiEnv(Env):
    """A two-player game: one machine, one action, one reward and one observation per seat.

    See the module docstring for the spaces. `num_actions` is per seat (every seat has as many).
    """

    def __init__(self, spec: GameSpec, config, rom_path=None):
        if spec.seats is None:
            raise ValueError(f"{spec.id} is a one-player game; two-player games: {', '.join(list_games(players=2))}")
        self.seats = spec.seats
        startup = spec.startup if spec.seats.startup is None else spec.seats.startup
        # the one-player Env refuses mirror (it has no second seat); this env applies it in _observe
        super().__init__(dataclasses.replace(spec, startup=startup), dataclasses.replace(config, mirror=False),
                         rom_path)
        self.spec, self.config = spec, config
        self._seat_masks = np.array([[0] + [1 << k for k in keys] for keys in spec.seats.action_keys], np.uint32)
        self._action_masks = self._seat_masks[0]  # num_actions: every seat has as many
        # per seat, the game's action for each action the seat plays (identity without mirror)
        mirrored = spec.seats.mirror_actions if config.mirror else None
        self._seat_actions = np.array([range(self.num_actions), mirrored or range(self.num_actions)], np.int32)

    @property
    def players(self) -> int:
        return self.seats.players

    @property
    def agents(self) -> tuple[str, ...]:
        """The seats' names as PettingZoo's Atari envs name them: first_0, second_0."""
        return ("first_0", "second_0")[: self.players]

    @property
    def turn_based(self) -> bool:
        return self.seats.turn_based

    @property
    def mirrored(self) -> bool:
        """Seat 1 sees and plays the mirror image (`mirror=True`)."""
        return self.config.mirror

    def mirror_action(self, actions) -> jax.Array:
        """(players,) actions as the seats play them -> the game's own, or back (an involution):
        seat 1's mapped through `Seats.mirror_actions` when `mirrored`, else unchanged."""
        return jnp.asarray(self._seat_actions)[jnp.arange(self.players), actions]

    @property
    def observation_shape(self) -> tuple[int, int, int]:
        """One seat's observation: the step's screens, then the player plane."""
        frames, height, width = super().observation_shape
        return (frames + 1, height, width)

    # --- the pure game ------------------------------------------------------------------------

    def step_env(self, key: jax.Array, state: EnvState, actions, params: EnvParams):
        """`Env.step_env` with one action per seat; a closed action (see `legal_action_mask`) is no-op."""
        actions = self._check_action(actions)
        actions = jnp.where(self.legal_action_mask(state)[jnp.arange(self.players), actions], actions, 0)
        if self.mirrored:
            actions = self.mirror_action(actions)
        return self._transition(key, state, actions, params)

    def current_player(self, state: EnvState) -> jax.Array:
        """int32: the seat to move in a turn-based game, -1 in a simultaneous one."""
        if not self.turn_based:
            return jnp.int32(-1)
        return jnp.asarray(self.seats.turn_fn(state.machine), jnp.int32)

    def legal_action_mask(self, state: EnvState) -> jax.Array:
        """bool (players, num_actions): the actions open to each seat now (no-op always is)."""
        everything = jnp.ones((self.players, self.num_actions), jnp.bool_)
        if not self.turn_based:
            return everything
        open_to_mover = everything[0]
        if self.seats.legal_fn is not None:
            open_to_mover = jnp.asarray(self.seats.legal_fn(state.machine), jnp.bool_).at[0].set(True)
        only_noop = jnp.arange(self.num_actions) == 0
        mover = self.current_player(state)
        masks = jnp.where((jnp.arange(self.players) == mover)[:, None], open_to_mover[None], only_noop[None])
        if self.mirrored:  # a seat's action a is the game's _seat_actions[seat, a]
            masks = jnp.take_along_axis(masks, jnp.asarray(self._seat_actions), axis=1)
        return masks

    def info(self, state: EnvState) -> dict[str, jax.Array]:
        """`Env.info` (score per seat) plus `current_player` and `legal_action_mask`."""
        return {**super().info(state), "current_player": self.current_player(state),
                "legal_action_mask": self.legal_action_mask(state)}

    # --- pieces -------------------------------------------------------------------------------

    @property
    def _action_shape(self) -> tuple[int, ...]:
        return (self.players,)

    def _keys_held(self, actions: jax.Array, game) -> jax.Array:
        """Either seat's key is held: the OR of the seats' masks."""
        held = jnp.asarray(self._seat_masks)[jnp.arange(self.players), actions]
        return jax.lax.reduce(held, np.uint32(0), jax.lax.bitwise_or, (0,))

    def _observe(self, screens) -> jax.Array:
        frames = super()._observe(screens)
        plane = jnp.arange(self.players, dtype=frames.dtype) * jnp.asarray(self.config.obs_scale, frames.dtype)
        planes = jnp.broadcast_to(plane[:, None, None, None], (self.players, 1, *frames.shape[1:]))
        if self.mirrored:  # seat 1 sees the screens flipped across the game's axis
            seen = jnp.stack([frames, jnp.flip(frames, axis=MIRROR_AXIS[self.seats.mirror])])
        else:
            seen = jnp.broadcast_to(frames[None], (self.players, *frames.shape))
        return jnp.concatenate([seen, planes], axis=1)

    def _score(self, machine: MachineState, game) -> jax.Array:
        scores = jnp.asarray(self.seats.score_fn(machine), jnp.float32)
        if scores.shape != (self.players,):
            raise ValueError(f"{self.spec.id}: Seats.score_fn must give ({self.players},) scores, got {scores.shape}")
        return scores


MIRROR_AXIS = {"left-right": -1, "top-bottom": -2}  # `Seats.mirror` -> the frames' axis it flips (W, H)


def make_multi(game: Union[str, GameSpec], *, rom=None, **options: Any) -> tuple[MultiEnv, EnvParams]:
    """Builds the two-player env of a game in `list_games(players=2)` (or your `GameSpec` with seats).

    Takes the same options as `octax_core.make` (`ENV_OPTIONS`), and `mirror` (see the module
    docstring) for the games `octax_core.env.config.mirrored_games()` lists.

    Raises:
        KeyError: unknown game id. ValueError: a one-player game (the message lists the two-player
        ones), `mirror=True` for a game without mirrored seats (the message lists those with),
        or an option out of range. TypeError: an unknown option.
    """
    spec = game if isinstance(game, GameSpec) else get_spec(game)
    config, params = make_config(spec, **options)
    return MultiEnv(spec, config, rom), params
