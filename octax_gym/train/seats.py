"""Self-play's envs: both seats of a two-player game as lanes, so the one rollout trains on them.

    lanes = SeatLanes(game)
    obs, state = lanes.reset(key, game, num_envs)           # num_envs two-seat envs: 2 * num_envs lanes
    obs, state, reward, terminated, truncated, final_obs = lanes.step(key, state, action)   # action (2N,)
    legal = lanes.legal_mask(state, game)                    # (2N, ACTIONS) bool, from each env's state

`Lanes` (envs.py) gives an agent one lane per env; here env e of `octax_core.make_multi(game)` is
lanes 2e (seat 0) and 2e + 1 (seat 1): each lane has its seat's observation (the screens and its
player plane, so one network knows which side it plays), its seat's reward and the env's shared
end. The rollout's arrays stay (num_steps, lanes, ...) and GAE runs per lane, i.e. per seat, with
no code of its own; only the env state is per env, (N, ...). The legal masks come from the state
(`MultiEnv.legal_action_mask`: in a turn-based game the seat not to move has only no-op), padded
to the networks' `ACTIONS` outputs, where `Lanes.legal_mask` gives a one-player game's static row.

With the `mirror` override (`--mirror`, a game with `Seats.mirror`: Cycles) both envs are
`make_multi(..., mirror=True)`: seat 1's lanes see the screen flipped and play the mirror image's
actions, so the one network plays both seats from seat 0's side (its player plane still tells
them apart); the evaluation's scripted opponents are made for that env (selfplay.py).

The training env autoresets (`Env.step`: the next episode drawn with the step's reset key); the
evaluation (selfplay.py) plays whole matches in a second env made without autoreset and with
`eval_noop_max` no-op starts, as the one-player evaluation's.
"""

from __future__ import annotations

from typing import Optional, Sequence

import jax
import jax.numpy as jnp
import numpy as np

import octax_core
from octax_gym.train.networks import ACTIONS

SEATS = 2


class SeatLanes:
    """The training and evaluation envs of a self-play run's one two-player game, seats as lanes."""

    def __init__(self, games: Sequence, overrides: Optional[dict] = None, eval_noop_max: int = 30,
                 roms: Optional[Sequence] = None):
        if len(games) != 1:
            raise ValueError(f"selfplay trains on one two-player game, got {len(games)}")
        game, rom = games[0], None if roms is None else roms[0]
        overrides = dict(overrides or {})
        try:
            self.env, self.params = octax_core.make_multi(game, rom=rom, autoreset=True, **overrides)
        except ValueError as exc:  # a one-player game: make_multi's message lists the two-player ones
            raise ValueError(f"selfplay: {exc}") from None
        eval_options = {**overrides, "noop_max": eval_noop_max}  # distinct matches (evaluate.py says why)
        self.eval_env, self.eval_params = octax_core.make_multi(game, rom=rom, autoreset=False, **eval_options)
        if self.env.num_actions > ACTIONS:
            raise ValueError(f"{self.env.spec.id} takes {self.env.num_actions} actions a seat; the networks have "
                             f"{ACTIONS}")
        self.num_actions = np.array([self.env.num_actions])
        self.legal = np.arange(ACTIONS)[None, :] < self.num_actions[:, None]  # (1, ACTIONS): every action ever open

    @property
    def games(self) -> tuple[str, ...]:
        return (self.env.spec.id,)

    @property
    def spec(self):
        return self.env.spec

    @property
    def compiler_options(self) -> dict:
        return self.env.compiler_options

    def max_episode_steps(self, game: int) -> int:
        return int(self.params.max_episode_steps)

    def reset(self, key: jax.Array, game, num_envs: int):
        """`num_envs` new games (2 * num_envs lanes: obs (2N, F + 1, H, W)), from keys split from `key`;
        `game` is the run's one game (index 0)."""
        obs, state = jax.vmap(self.env.reset, in_axes=(0, None))(jax.random.split(key, num_envs), self.params)
        return _lanes(obs), state

    def step(self, key: jax.Array, state, action: jax.Array):
        """One step of every env, `action` (2N,) the lanes' (seat 0, seat 1 of env 0, then env 1's...);
        returns what `Lanes.step` returns, per lane: a seat's reward is its own, the end is the env's."""
        num_envs = action.shape[0] // SEATS
        obs, state, reward, terminated, truncated, info = jax.vmap(self.env.step, in_axes=(0, 0, 0, None))(
            jax.random.split(key, num_envs), state, action.reshape(num_envs, SEATS), self.params)
        both = lambda flag: jnp.repeat(flag, SEATS)  # noqa: E731  (N,) -> (2N,): one end, two seats
        return (_lanes(obs), state, reward.reshape(-1), both(terminated), both(truncated),
                _lanes(info["final_observation"]))

    def legal_mask(self, state, game) -> jax.Array:
        """(2N, ACTIONS) bool: each lane's actions open now, from its env's state."""
        legal = jax.vmap(self.env.legal_action_mask)(state)  # (N, 2, num_actions)
        legal = legal.reshape(-1, legal.shape[-1])
        return jnp.pad(legal, ((0, 0), (0, ACTIONS - legal.shape[-1])))


def _lanes(x: jax.Array) -> jax.Array:
    """(N, 2, ...) per env and seat -> (2N, ...) per lane."""
    return x.reshape((-1,) + x.shape[2:])
