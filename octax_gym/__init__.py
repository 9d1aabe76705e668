"""octax_gym: CHIP-8, SUPER-CHIP and XO-CHIP games as Gymnasium environments over the batched
JAX core (`octax_core`).

    import gymnasium as gym
    import octax_gym

    gym.register_envs(octax_gym)                       # importing registers octax/<Game>-v0
    env = gym.make("octax/Pong-v0", render_mode="rgb_array")
    envs = gym.make_vec("octax/Pong-v0", num_envs=64, backend="torch")

`OctaxVectorEnv` is a real `gymnasium.vector.VectorEnv` (one jitted call per step), `OctaxEnv` the
single env. This package imports `octax_core`, never the reverse; torch, SB3 and TorchRL are
imported only when asked for. See docs/gymnasium.md.

Two-player games: `MultiAgentVectorEnv` / `make_multi_vec` (both seats, batched),
`octax_gym.pettingzoo` (`parallel_env`, `env`), and any two-player id with `opponent=` for one seat
against a fixed opponent (`octax_gym.opponent`). See docs/pettingzoo.md.

Many games in one batch: `gym.make_vec("octax/Mix-v0", num_envs=N, games=[...])` (`MIX_ENV_ID`,
`octax_core.make_mix`). See docs/mix.md.
"""

from octax_core import __version__  # the installed distribution's, read in one place
from octax_gym.action_check import IllegalMoveError, InvalidActionError
from octax_gym.choices import UnknownOptionError
from octax_gym.env import OctaxEnv
from octax_gym.game_names import NAMESPACE, env_id
from octax_gym.multi_vector import MultiAgentVectorEnv, make_multi_vec
from octax_gym.opponent import OpponentRequiredError
from octax_gym.registration import MIX_ENV_ID, register_all, register_game, register_mix, register_two_player
from octax_gym.render import PALETTES
from octax_gym.vector import OctaxVectorEnv

ENV_IDS = tuple(register_all())  # the one-player envs (`octax_core.list_games()`)
TWO_PLAYER_ENV_IDS = tuple(register_two_player())  # `list_games(players=2)`: with opponent=, or MultiAgentVectorEnv
register_mix()  # octax/Mix-v0: many games in one batch (games=[...])

# The adapters import torch, SB3 or TorchRL, the dataset collector Minari: loaded on first use
# (`octax_gym.make_sb3_vec_env`), never by `import octax_gym`.
_LAZY = {"make_sb3_vec_env": "octax_gym.sb3", "PPO_KWARGS": "octax_gym.sb3",
         "make_torchrl_env": "octax_gym.torchrl", "collect_dataset": "octax_gym.datasets"}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'octax_gym' has no attribute {name!r}")


__all__ = ["ENV_IDS", "IllegalMoveError", "MIX_ENV_ID", "InvalidActionError", "MultiAgentVectorEnv", "NAMESPACE", "OctaxEnv",
           "OctaxVectorEnv", "OpponentRequiredError", "PALETTES", "TWO_PLAYER_ENV_IDS", "UnknownOptionError", "env_id",
           "__version__", "make_multi_vec", "register_all", "register_game", "register_mix", "register_two_player", *_LAZY]
