"""Offline training (behaviour cloning, discrete CQL) as a configuration of the one loop.

    octax-gym train bc --dataset octax/Flak/expert-v0 --num-seeds 2
    octax-gym train cql --dataset octax/Flak/medium-v0

Where PPO and PQN collect a rollout, an offline trainer's `collect` draws `num_envs * num_steps`
transitions of a Minari dataset (uniformly, with replacement, inside the compiled program), and
the same `learn` (rollout.py: `update_epochs` passes of `num_minibatches` optimizer steps) trains
on them; the loop's evaluation, log, figure, agents and resume are the online runs' own. A row's
`step` counts the transitions drawn per agent. The dataset is loaded once onto the device
(`octax_gym.datasets.load_transitions`) and handed to the compiled update as an argument, not
baked into the program as a constant.

Both use the PQN network (networks.QNetwork: the paper's CNN, a 256-unit LayerNorm layer, one
output per action) masked to the game's actions:

- bc: the outputs are logits; cross-entropy with the dataset's actions. Sampled evaluation: the
  softmax.
- cql: the outputs are Q-values; a one-step TD loss (Huber, to a target network copied every
  `target_every` updates) plus CQL's regulariser `cql_alpha * (logsumexp_a Q(s, a) - Q(s, a_data))`
  (Kumar et al., 2020, the discrete-action form they used on Atari). Sampled evaluation:
  epsilon-greedy at `eval_epsilon`, as PQN's.

The run's game and env options are the dataset's (`dataset_env`: the suite caps episodes at 2,000
steps), so agents are evaluated in the env the data came from.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import optax

from octax_gym.train import rollout as shared
from octax_gym.train.algorithm import Trainer
from octax_gym.train.config import ENV_FLAGS, TrainConfig
from octax_gym.train.envs import Lanes
from octax_gym.train.networks import QNetwork, masked
from octax_gym.train.pqn import epsilon_greedy

METRICS = {"bc": ("loss", "accuracy", "learning_rate"), "cql": ("td_loss", "cql_loss", "q_mean", "learning_rate")}


class OfflineRunner(NamedTuple):
    """One offline agent between updates: no lanes, a target network (CQL's; BC's is unused)."""

    params: Any
    opt_state: Any
    target: Any
    key: jax.Array
    updates: jax.Array  # () int32
    game: jax.Array  # () int32, an index into the run's games


def dataset_env(dataset_id: str) -> tuple[str, tuple]:
    """The game of a Minari dataset and the env options it was collected with (those a run may set,
    `config.ENV_FLAGS`), as `(game, env_overrides)`.

    Raises:
        FileNotFoundError: no dataset of that id (the message says where datasets are looked for).
    """
    from octax_gym.datasets.storage import import_minari

    minari = import_minari()
    try:
        dataset = minari.load_dataset(dataset_id)
    except (FileNotFoundError, ValueError, KeyError) as exc:
        raise FileNotFoundError(f"--dataset: no Minari dataset {dataset_id!r} ({exc}); collect one with "
                                "`octax-gym dataset collect` or `octax-gym dataset suite` (docs/datasets.md)") from exc
    kwargs = dataset.spec.env_spec.kwargs
    return kwargs["game"], tuple((name, kwargs[name]) for name in ENV_FLAGS if kwargs.get(name) is not None)


def make_trainer(config: TrainConfig, lanes: Lanes) -> Trainer:
    """BC or CQL on `config.dataset` for the run's one game (the dataset's)."""
    from octax_gym.datasets import load_transitions

    game, _ = dataset_env(config.dataset)
    if list(lanes.games) != [game]:
        raise ValueError(f"{config.algorithm} trains on {config.dataset}, a dataset of {game}: the run's games must "
                         f"be ({game},), got ({', '.join(lanes.games)})")
    data = load_transitions(config.dataset).device_put()
    network, optimizer = QNetwork(layout=config.network_layout), shared.make_optimizer(config)
    legal_of = jnp.asarray(lanes.legal)
    cql = config.algorithm == "cql"
    obs_shape = tuple(data.observations.shape[1:])

    def init(key, game):
        key, net_key = jax.random.split(key)
        params = network.init(net_key, jnp.zeros((1, *obs_shape), jnp.uint8))
        return OfflineRunner(params, optimizer.init(params), params, key, jnp.int32(0), game)

    def scores(params, obs, game):
        return masked(network.apply(params, obs), legal_of[game])

    def collect(runner: OfflineRunner, data):
        key, draw_key = jax.random.split(runner.key)
        batch = data.sample(draw_key, config.batch_size)
        # Laid out (num_steps, num_envs, ...) as a rollout is, for learn's reshape.
        batch = jax.tree.map(lambda x: x.reshape((config.num_steps, config.num_envs) + x.shape[1:]), batch)
        copy = (runner.updates % config.target_every == 0) if cql else jnp.bool_(False)
        target = jax.tree.map(lambda t, p: jnp.where(copy, p, t), runner.target, runner.params)
        next_q = scores(target, batch.next_obs.reshape((-1,) + obs_shape), runner.game).max(-1).reshape(
            batch.reward.shape) if cql else jnp.zeros_like(batch.reward)
        td_target = batch.reward + config.gamma * (1.0 - batch.terminated.astype(jnp.float32)) * next_q
        games = jnp.broadcast_to(runner.game, batch.action.shape)
        no_episodes = {"finished_return_sum": jnp.float32(0), "finished_episodes": jnp.int32(0)}
        return runner._replace(key=key, target=target), (batch.obs, games, batch.action, td_target), no_episodes

    def loss(params, minibatch):
        obs, game, action, td_target = minibatch
        out = masked(network.apply(params, obs), legal_of[game])
        if not cql:
            loss = optax.softmax_cross_entropy_with_integer_labels(out, action).mean()
            return loss, {"loss": loss, "accuracy": (jnp.argmax(out, -1) == action).mean()}
        q_taken = jnp.take_along_axis(out, action[:, None], 1)[:, 0]
        td_loss = optax.huber_loss(q_taken, td_target).mean()
        cql_loss = (jax.nn.logsumexp(out, axis=-1) - q_taken).mean()
        return td_loss + config.cql_alpha * cql_loss, {"td_loss": td_loss, "cql_loss": cql_loss,
                                                       "q_mean": q_taken.mean()}

    def greedy(params, key, obs, game):
        return jnp.argmax(scores(params, obs, game), axis=1).astype(jnp.int32)

    def sampled(params, key, obs, game):
        if cql:
            return epsilon_greedy(network.apply(params, obs), key, config.eval_epsilon, legal_of[game])
        return jax.random.categorical(key, scores(params, obs, game)).astype(jnp.int32)

    return Trainer(config.algorithm.upper(), network, init, collect, shared.make_learn(config, optimizer, loss),
                   greedy, sampled, METRICS[config.algorithm], lambda i: {"learning_rate": config.learning_rate_at(i)},
                   data)
