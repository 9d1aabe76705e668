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

import importlib
import importlib.abc
import importlib.machinery
import sys

from octax_core import __version__  # the installed distribution's, read in one place
from octax_gym.envs.choices import UnknownOptionError
from octax_gym.envs.env import OctaxEnv
from octax_gym.envs.game_names import NAMESPACE, env_id
from octax_gym.envs.multi_vector import MultiAgentVectorEnv, make_multi_vec
from octax_gym.envs.registration import MIX_ENV_ID, register_all, register_game, register_mix, register_two_player
from octax_gym.envs.render import PALETTES
from octax_gym.envs.vector import OctaxVectorEnv
from octax_gym.step.action_check import IllegalMoveError, InvalidActionError
from octax_gym.step.opponent import OpponentRequiredError

ENV_IDS = tuple(register_all())  # the one-player envs (`octax_core.list_games()`)
TWO_PLAYER_ENV_IDS = tuple(register_two_player())  # `list_games(players=2)`: with opponent=, or MultiAgentVectorEnv
register_mix()  # octax/Mix-v0: many games in one batch (games=[...])

# The adapters import torch, SB3 or TorchRL, the dataset collector Minari: loaded on first use
# (`octax_gym.make_sb3_vec_env`), never by `import octax_gym`.
_LAZY = {"make_sb3_vec_env": "octax_gym.integrations.sb3", "PPO_KWARGS": "octax_gym.integrations.sb3",
         "make_torchrl_env": "octax_gym.integrations.torchrl", "collect_dataset": "octax_gym.datasets"}


# Old dotted name -> new: the modules that moved into envs/, step/ and integrations/ (issue 40). The
# old names stay importable, as the same module objects (sys.modules[old] is sys.modules[new]), so
# code, pickles and monkeypatch targets written against them keep working. Nothing in the package
# imports an old name.
_MOVED = {
    "octax_gym.env": "octax_gym.envs.env",
    "octax_gym.vector": "octax_gym.envs.vector",
    "octax_gym.multi_vector": "octax_gym.envs.multi_vector",
    "octax_gym.pettingzoo": "octax_gym.envs.pettingzoo",
    "octax_gym.registration": "octax_gym.envs.registration",
    "octax_gym.render": "octax_gym.envs.render",
    "octax_gym.game_names": "octax_gym.envs.game_names",
    "octax_gym.choices": "octax_gym.envs.choices",
    "octax_gym.compiled_step": "octax_gym.step.compiled_step",
    "octax_gym.action_check": "octax_gym.step.action_check",
    "octax_gym.opponent": "octax_gym.step.opponent",
    "octax_gym.backends": "octax_gym.step.backends",
    "octax_gym.sharding": "octax_gym.step.sharding",
    "octax_gym.distributed": "octax_gym.step.distributed",
    "octax_gym.handshake": "octax_gym.step.handshake",
    "octax_gym.sb3": "octax_gym.integrations.sb3",
    "octax_gym.torchrl": "octax_gym.integrations.torchrl",
}


class _MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Imports an old name of `_MOVED` as the module at its new name: no second copy of the
    module (its classes, its compiled functions' caches) is ever made."""

    def find_spec(self, fullname, path=None, target=None):
        new = _MOVED.get(fullname)
        return None if new is None else importlib.machinery.ModuleSpec(fullname, self, loader_state=new)

    def create_module(self, spec):
        module = importlib.import_module(spec.loader_state)
        spec.loader_state = module.__spec__  # the import system sets the old name's spec on it next
        return module

    def exec_module(self, module):
        module.__spec__ = module.__spec__.loader_state  # its own spec back: it lives at the new name


sys.meta_path[:] = [f for f in sys.meta_path if type(f).__name__ != _MovedModules.__name__]  # once, on reload too
sys.meta_path.insert(0, _MovedModules())


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    if f"octax_gym.{name}" in _MOVED:  # `octax_gym.vector` as an attribute, as before the move
        return importlib.import_module(f"octax_gym.{name}")
    raise AttributeError(f"module 'octax_gym' has no attribute {name!r}")


__all__ = ["ENV_IDS", "IllegalMoveError", "MIX_ENV_ID", "InvalidActionError", "MultiAgentVectorEnv", "NAMESPACE", "OctaxEnv",
           "OctaxVectorEnv", "OpponentRequiredError", "PALETTES", "TWO_PLAYER_ENV_IDS", "UnknownOptionError", "env_id",
           "__version__", "make_multi_vec", "register_all", "register_game", "register_mix", "register_two_player", *_LAZY]
