"""Training in pure JAX (flax, optax): the paper's PPO and PQN on octax games, many agents in one program;
BC and CQL offline on a dataset.

    from octax_gym.train import TrainConfig, preset, train
    config = preset("cpu", "ppo", games=("Airplane", "Deep8"), num_seeds=2)
    summary = train(config, "runs/ppo")

or from the shell, `octax-gym train ppo --games Airplane,Deep8 --num-seeds 2 --out-dir runs/ppo`.
One module per job: `networks` (the CNN, its PPO and PQN heads), `envs` (the run's games in one
mix, each agent's lanes fixed to its game), `many` (the agent axis), `rollout` (runner, rollout,
minibatch epochs), `ppo` and `pqn` (acting, targets, losses), `offline` (BC and CQL on a Minari
dataset: a draw instead of a rollout), `evaluate`, `log` (progress.csv),
`figure`, `report` (IQM and intervals), `checkpoints`, `parallel` (`--devices all`), `config`,
`presets`, `seats` and `selfplay` (both seats of a two-player game as lanes, the pool of past
selves, evaluation in matches: `octax-gym train selfplay`), and `loop` (the one loop). Needs the `train` extra: pip install 'octax-gym[train]'.
See docs/training.md.
"""

try:
    import flax  # noqa: F401
    import optax  # noqa: F401
except ImportError as _exc:  # a named error, not a traceback from deep inside a module
    raise ImportError(f"octax_gym.train needs flax and optax (the train extra): pip install 'octax-gym[train]' "
                      f"({_exc})") from _exc

from octax_gym.train.config import ALGORITHMS, TrainConfig, resolve_games
from octax_gym.train.loop import train
from octax_gym.train.presets import PRESETS, preset

__all__ = ["ALGORITHMS", "PRESETS", "TrainConfig", "preset", "resolve_games", "train"]
