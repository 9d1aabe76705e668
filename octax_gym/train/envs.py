"""The run's envs: one `octax_core.make_mix` of its games, each agent's lanes fixed to its game.

    lanes = Lanes(["Airplane", "Deep8"], overrides={}, eval_noop_max=30)
    obs, state = lanes.reset(key, game, num_envs)                 # one agent's lanes, all on `game`
    obs, state, reward, terminated, truncated, final_obs = lanes.step(key, state, action)

A mix's own autoreset draws the next episode's game from its weights; here every reset, first and
automatic, is forced to the lane's game (`EnvState.game`), so an agent only ever plays its game.
The step is `Env.step`'s, key for key (split into the step's and the reset's; the reset draws its
start with the reset key, as `make(game)` does), so a lane plays exactly what an env of
`octax_core.make(game, autoreset=True)` plays from the same keys and actions, whichever games
share the mix (tests/train check it). A run of one game is a mix of one: the same program.

Why one mix and not an env per game: G games under one `vmap` are one compiled step, where G envs
would be G programs traced side by side. The evaluation env is a second mix, made without
autoreset and with `eval_noop_max` no-op starts (evaluate.py says why); `eval_games` (games the
agents are evaluated on but never train on: a generated family's held-out variants) join that mix
alone, after the run's games, so game g < G is the same game in both mixes and the training mix is
the one a run without them makes.
"""

from __future__ import annotations

from typing import Optional, Sequence

import jax
import jax.numpy as jnp
import numpy as np

import octax_core
from octax_core.emulator.gate import when_any
from octax_gym.train.networks import ACTIONS


class Lanes:
    """The training and evaluation mixes of a run's games, and each game's legal actions."""

    def __init__(self, games: Sequence, overrides: Optional[dict] = None, eval_noop_max: int = 30,
                 roms: Optional[Sequence] = None, eval_games: Sequence = (), eval_roms: Optional[Sequence] = None):
        overrides = dict(overrides or {})
        self.env, self.params = octax_core.make_mix(list(games), roms=roms, autoreset=False, **overrides)
        eval_options = {**overrides, "noop_max": eval_noop_max}
        all_roms = None
        if roms is not None or eval_roms is not None:
            all_roms = list(roms or [None] * len(games)) + list(eval_roms or [None] * len(eval_games))
        self.eval_env, self.eval_params = octax_core.make_mix(list(games) + list(eval_games), roms=all_roms,
                                                              autoreset=False, **eval_options)
        # each game's own, the eval_games' after the run's (rows G.. of `legal`: what greedy and sampled index)
        self.num_actions = np.array([len(spec.action_keys) + 1 for spec in self.eval_env.specs])
        if self.num_actions.max() > ACTIONS:
            raise ValueError(f"{self.eval_env.games[int(self.num_actions.argmax())]} takes {self.num_actions.max()} "
                             f"actions; the networks have {ACTIONS}")
        self.legal = np.arange(ACTIONS)[None, :] < self.num_actions[:, None]  # (G, ACTIONS) bool

    @property
    def games(self) -> tuple[str, ...]:
        return self.env.games

    @property
    def compiler_options(self) -> dict:
        return self.env.compiler_options

    def max_episode_steps(self, game: int) -> int:
        return int(np.asarray(self.params.max_episode_steps)[game])

    def reset(self, key: jax.Array, game, num_envs: int, evaluation: bool = False):
        """`num_envs` new episodes of `game` (an index into `games`, or one per lane), from
        `num_envs` keys split from `key`."""
        env, params = (self.eval_env, self.eval_params) if evaluation else (self.env, self.params)
        keys = jax.random.split(key, num_envs)
        games = jnp.broadcast_to(jnp.asarray(game, jnp.int32), (num_envs,))
        return jax.vmap(lambda k, g: env.reset(k, params, game=g))(keys, games)

    def step(self, key: jax.Array, state, action: jax.Array):
        """One step of a batch of training lanes, each restarting its own game where an episode ended.

        Returns obs, state, reward, terminated, truncated and the ended episodes' last observations
        (where truncated, what a bootstrap reads).
        """
        keys = jax.random.split(key, action.shape[0])
        return jax.vmap(self._step_one)(keys, state, action)

    def legal_mask(self, state, game) -> jax.Array:
        """(num_envs, ACTIONS) bool: each lane's legal actions, its game's static row (`legal`)
        (seats.py's two-seat lanes read theirs from the state: the one rollout takes either)."""
        return jnp.broadcast_to(jnp.asarray(self.legal)[game], (state.done.shape[0], ACTIONS))

    def eval_step(self, key: jax.Array, state, action: jax.Array):
        """One step of a batch of evaluation lanes (no autoreset: an ended episode stands still)."""
        keys = jax.random.split(key, action.shape[0])
        return jax.vmap(lambda k, s, a: self.eval_env.step(k, s, a, self.eval_params))(keys, state, action)

    def _step_one(self, key, state, action):
        step_key, reset_key = jax.random.split(key)  # as Env.step splits it
        obs, state, reward, terminated, truncated, _ = self.env.step_env(step_key, state, action, self.params)
        final_obs = obs
        obs, state = when_any(state.done, self._restart_where, (obs, state), (reset_key, state.done, state.game))
        return obs, state, reward, terminated, truncated, final_obs

    def _restart_where(self, operands, inputs):
        """A new episode of the lane's own game where its episode ended; bit for bit the same
        operands elsewhere (`when_any`'s contract)."""
        (obs, state), (key, mask, game) = operands, inputs
        fresh = self.env.reset_env(key, self.params, game)
        return jax.tree.map(lambda new, old: jnp.where(mask, new, old), fresh, (obs, state))
