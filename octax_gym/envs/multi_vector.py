"""`MultiAgentVectorEnv`: both seats of a two-player game, `num_envs` games stepped by one jitted call.

    import octax_gym
    envs = octax_gym.make_multi_vec("SpaceRacer", num_envs=64, backend="torch")
    obs, info = envs.reset(seed=0)                   # obs (64, 2, frames_per_step + 1, 32, 64)
    obs, rewards, terminated, truncated, info = envs.step(actions)   # actions (64, 2), rewards (64, 2)

It is `OctaxVectorEnv` (a subclass) over the two-player core env (`octax_core.make_multi`): the
same compiled step, seeding, autoreset modes, backends (torch by DLPack, without copies), device,
rendering and deferred device-action checks; only the action batch (num_envs, 2), the per-seat
rewards and observations, and the turn-based checks differ. The PettingZoo envs
(`octax_gym.envs.pettingzoo`) run on it with num_envs=1. See docs/pettingzoo.md.
"""

from __future__ import annotations

import inspect
from typing import Any, Optional, Union

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode

from octax_core.env.config import check_option_names
from octax_gym.envs import render
from octax_gym.envs.vector import OctaxVectorEnv
from octax_gym.step.compiled_step import GYM_ENV_OPTIONS


class MultiAgentVectorEnv(OctaxVectorEnv):
    """`num_envs` two-player games, both seats played by the caller, stepped by one jitted call.

    Agents (seats): `agents` = ("first_0", "second_0"), PettingZoo's Atari names; seat 0 is the
    game's first player (`Seats.names`).

    Observation: uint8 (num_envs, 2, frames_per_step + 1, H, W): per env, per seat, the step's
    screens (the same for both seats), then a player plane, 0 everywhere for seat 0 and
    `obs_scale` for seat 1, so one policy can play either side and know which.
    Action: int (num_envs, 2), one per env and seat, 0..n-1 (0 = no key; `Seats.action_keys`); both
    seats' keys are held on the one keypad together.
    Reward: float32 (num_envs, 2), the change of each seat's score. terminated, truncated: bool
    (num_envs,), shared by the seats (one machine, one episode).
    info: score (num_envs, 2), lives, episode_step, current_player (num_envs,): the seat to move in a
    turn-based game, -1 in a simultaneous one; legal_action_mask bool (num_envs, 2, n): the actions
    open to each seat now (no-op always is; in a turn-based game the seat whose turn it is not
    has no-op alone). Each key comes with its `_` mask, as in `OctaxVectorEnv`.

    Spaces: `single_observation_space` is one env's observation, Box (2, F+1, H, W), and
    `observation_space` the batch's, so that `obs in envs.observation_space` holds;
    `single_action_space` is MultiDiscrete([n, n]) (one action per seat) and `action_space` its
    batch, MultiDiscrete of shape (num_envs, 2). One seat's own spaces, what a per-agent policy
    sees, are `agent_observation_space` (Box (F+1, H, W)) and `agent_action_space` (Discrete(n)).

    Errors, before the step for actions on the host (numpy, lists): TypeError for non-integers,
    ValueError for a shape other than (num_envs, 2), `InvalidActionError` for an action outside
    0..n-1 (the message names the env and the seat), and `IllegalMoveError` for an action the
    legal mask closes: a move by the seat whose turn it is not, or one the mover's
    `Seats.legal_fn` closes (rows whose episode has ended are not checked: their actions are
    ignored). Device actions (JAX arrays, torch tensors) are checked inside the jitted step and
    raise at a later call, as in `OctaxVectorEnv` (`octax_gym.step.action_check`); a bad one is played
    as no-op.

    Seeding and autoreset are `OctaxVectorEnv`'s: env i of a batch seeded s plays the game of a
    batch of one seeded s + i; `autoreset_mode` NEXT_STEP (default), SAME_STEP or DISABLED.

    Args:
        game: a two-player game's id ("SpaceRacer"; `octax_core.list_games(players=2)`), its
            Gymnasium id, in any case, or a `GameSpec` with `seats`.
        num_envs, autoreset_mode, backend, device, render_mode, render_scale, palette, rom,
        **env_options: as `OctaxVectorEnv` (rendering shows the one screen both seats see).

    Raises:
        UnknownOptionError: an unknown game (the message lists the two-player ones).
        ValueError: a one-player game.
    """

    def __init__(self, game: Any, num_envs: int = 1, *,
                 autoreset_mode: Union[AutoresetMode, str] = AutoresetMode.NEXT_STEP,
                 backend: str = "numpy", device: Any = None, render_mode: Optional[str] = None,
                 render_scale: int = render.DEFAULT_RENDER_SCALE, palette: Optional[render.PaletteArg] = None,
                 rom=None, **env_options):
        check_option_names(env_options, MULTI_KEYWORDS, type(self).__name__)
        self._setup(game, num_envs, autoreset_mode, backend, device, render_mode, render_scale, palette, rom,
                    env_options, players=2)
        num_actions = self.core_env.num_actions
        self.agent_observation_space = self.single_observation_space  # (F+1, H, W): the core's per seat
        self.agent_action_space = spaces.Discrete(num_actions)
        self.single_observation_space = spaces.Box(0, self.core_env.observation_high,
                                                   (2, *self.core_env.observation_shape), np.uint8)
        self.single_action_space = spaces.MultiDiscrete([num_actions, num_actions])
        self.observation_space = gymnasium.vector.utils.batch_space(self.single_observation_space, self.num_envs)
        self.action_space = gymnasium.vector.utils.batch_space(self.single_action_space, self.num_envs)

    @property
    def num_actions(self) -> int:
        """Actions per seat (no-op included)."""
        return self.core_env.num_actions

    @property
    def turn_based(self) -> bool:
        return self.core_env.turn_based

    def action_masks(self) -> np.ndarray:
        """bool (num_envs, 2, n): the actions open to each seat now (`info["legal_action_mask"]`)."""
        if self._info is None:
            raise gymnasium.error.ResetNeeded("call reset() before action_masks()")
        return np.asarray(self._info["legal_action_mask"])


def make_multi_vec(game: Any, num_envs: int = 1, **kwargs) -> MultiAgentVectorEnv:
    """`MultiAgentVectorEnv(game, num_envs, **kwargs)`: `game` a two-player game's id or Gymnasium id
    ("SpaceRacer", "octax/SpaceRacer-v0") or a `GameSpec` with seats."""
    return MultiAgentVectorEnv(game, num_envs, **kwargs)


# Every keyword the multi-agent vector env takes: its own and the core's env options.
MULTI_KEYWORDS = tuple(name for name, parameter in inspect.signature(MultiAgentVectorEnv.__init__).parameters.items()
                       if parameter.kind == inspect.Parameter.KEYWORD_ONLY) + GYM_ENV_OPTIONS
