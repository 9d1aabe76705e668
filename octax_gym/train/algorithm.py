"""What the loop needs of an algorithm (`Trainer`), and the registry of algorithms by name.

An algorithm is pure functions of one agent: `init(key, game) -> runner`, an update in two halves
(`collect(runner) -> (runner, batch, metrics)`: the rollout and the targets; `learn(runner,
batch) -> (runner, stats)`: the minibatch epochs) and its two evaluated policies. The halves are
apart so that an algorithm that collects no rollout (offline training: a batch drawn from a
dataset) keeps the same epochs. PPO and PQN differ by how they act, their targets and their loss
(ppo.py, pqn.py), not by their loop: both build on rollout.py.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

from octax_gym.train.config import TrainConfig
from octax_gym.train.envs import Lanes


class Trainer(NamedTuple):
    """One algorithm for a run's lanes: pure functions of one agent, jittable and vmappable."""

    name: str  # "PPO", "PQN": titles and the progress bar
    network: Any  # the flax module
    init: Callable  # (key, game) -> runner
    collect: Callable  # runner [, data] -> (runner, batch, metrics): one rollout (or dataset draw) and its targets
    learn: Callable  # (runner, batch) -> (runner, stats): the epochs of minibatch steps
    greedy: Callable  # (params, key, obs, game) -> actions: the largest logit or Q-value of the game's
    sampled: Callable  # (params, key, obs, game) -> actions: PPO's policy, PQN's eval epsilon-greedy
    metric_names: tuple[str, ...]  # per-update metrics, averaged between evaluations in the CSV
    host_metrics: Callable  # update index -> {name: value} for schedules (learning rate, epsilon)
    data: Any = None  # what `collect` reads besides the runner, an argument of the compiled update (offline: the dataset)


def make_trainer(config: TrainConfig, lanes: Lanes) -> Trainer:
    """The `config.algorithm` trainer for `lanes`."""
    if config.algorithm in ("ppo", "multitask", "selfplay"):  # selfplay: PPO on two-seat lanes (selfplay.py)
        from octax_gym.train import ppo
        return ppo.make_trainer(config, lanes)
    if config.algorithm == "pqn":
        from octax_gym.train import pqn
        return pqn.make_trainer(config, lanes)
    if config.algorithm in ("bc", "cql"):
        from octax_gym.train import offline
        return offline.make_trainer(config, lanes)
    raise ValueError(f"algorithm must be one of ppo, pqn, multitask, selfplay, bc, cql, got {config.algorithm!r}")
