"""The part of an update every algorithm shares: the runner, the rollout and the minibatch epochs.

    runner, traj = rollout(runner, act_arg)        # num_steps steps of the agent's lanes under lax.scan
    batch = <the algorithm's targets from traj>    # PPO: GAE; PQN: Q(lambda) returns
    runner, stats = learn(runner, batch)           # update_epochs shuffled passes of minibatch steps

Everything here is a pure function of one agent; `loop.train` maps it over agents (many.py).
An algorithm (ppo.py, pqn.py) brings how it acts, the value it bootstraps from, its targets and
its loss.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import optax

from octax_gym.train.config import TrainConfig
from octax_gym.train.envs import Lanes
from octax_gym.train.many import any_over_agents, vmapped


class RunnerState(NamedTuple):
    """One agent between updates: its network and optimizer, its lanes mid-episode, its key."""

    params: Any
    opt_state: Any
    env_state: Any  # batched octax_core.EnvState, (num_envs, ...)
    obs: jax.Array  # (num_envs, F, 32, 64) uint8
    episode_return: jax.Array  # (num_envs,) float32, return so far of each running episode
    key: jax.Array
    updates: jax.Array  # () int32: updates done, for schedules (PQN's epsilon)
    game: jax.Array  # () int32: the agent's game, an index into the run's games; multitask: (num_envs,), per lane
    pool: Any = None  # selfplay's past selves (selfplay.Pool); None elsewhere, so no leaf of other runners


class Transition(NamedTuple):
    """One step of the lanes; a rollout stacks `num_steps` of them, each field (num_steps, lanes, ...)
    (lanes: `num_envs`, or self-play's 2 * `num_envs` seats)."""

    obs: jax.Array  # (lanes, F, 32, 64) uint8: what the policy saw
    legal: jax.Array  # (lanes, ACTIONS) bool: the actions open to it (the lanes' `legal_mask`)
    action: jax.Array  # (lanes,) int32
    policy_out: Any  # what `act` kept besides the action: PPO's log-prob and value, PQN's max Q
    reward: jax.Array  # (num_envs,) float32, plus gamma * bootstrap(final obs) where truncated
    done: jax.Array  # (num_envs,) bool, terminated | truncated: targets do not look past it
    finished_return: jax.Array  # (num_envs,) float32: the episode's return where it ended this step, else 0


def make_optimizer(config: TrainConfig) -> optax.GradientTransformation:
    """Adam after global-norm clipping; the rate decays linearly to 0 with `anneal_lr`."""
    lr = config.learning_rate
    if config.anneal_lr:
        lr = optax.linear_schedule(lr, 0.0, config.num_updates * config.update_epochs * config.num_minibatches)
    return optax.chain(optax.clip_by_global_norm(config.max_grad_norm), optax.adam(lr))


def make_init(config: TrainConfig, lanes: Lanes, network, optimizer: optax.GradientTransformation,
              net_input: Callable = lambda obs, game: obs) -> Callable:
    """`init(key, game) -> RunnerState`: fresh network params, optimizer state and `num_envs`
    lanes of `game` (one game, or one per lane) just reset. The network's init reads the game only
    where `net_input` gives it (a multi-task agent): agents of one seed start from the same weights
    whatever their game."""
    def init(key: jax.Array, game: jax.Array) -> RunnerState:
        key, net_key, env_key = jax.random.split(key, 3)
        obs, env_state = lanes.reset(env_key, game, config.num_envs)
        params = network.init(net_key, net_input(obs[:1], jnp.broadcast_to(game, (config.num_envs,))[:1]))
        return RunnerState(params, optimizer.init(params), env_state, obs,
                           jnp.zeros(obs.shape[0], jnp.float32), key, jnp.int32(0), game)

    return init


def make_rollout(config: TrainConfig, lanes: Lanes, act: Callable, bootstrap: Callable) -> Callable:
    """`rollout(runner, act_arg) -> (runner, traj)`: `config.num_steps` steps of the agent's lanes
    under `lax.scan`, `traj` a `Transition` of (num_steps, lanes, ...) arrays.

    Args:
      act: `(params, key, obs, game, legal, act_arg) -> (action, policy_out)`, the behaviour policy
        on a batch of observations (`game`: the agent's game, or one per lane; `legal`, (lanes,
        ACTIONS) bool, the actions open to each lane now, from `lanes.legal_mask`); `policy_out` (a
        pytree of (lanes, ...) arrays) is kept for the targets and the loss. `act_arg` is what the
        policy takes per rollout (PQN's epsilon; PPO's None; self-play's past self and its lanes).
      bootstrap: `(params, obs, game) -> (lanes,)` value of observations (PPO's critic, PQN's
        max Q), credited to a truncated episode's last reward.
    """
    shared = vmapped(config.agent_map, len(config.agent_names))  # a predicate all agents share keeps the cond
    def rollout(runner: RunnerState, act_arg=None):
        def env_step(runner: RunnerState, _):
            key, action_key, step_key = jax.random.split(runner.key, 3)
            legal = lanes.legal_mask(runner.env_state, runner.game)
            action, policy_out = act(runner.params, action_key, runner.obs, runner.game, legal, act_arg)
            obs, env_state, reward, terminated, truncated, final_obs = lanes.step(step_key, runner.env_state, action)
            # Partial-episode bootstrapping: a time limit is not a terminal state, so a truncated
            # episode is credited gamma * value(its last observation). Rare, so the network runs only then.
            final_value = jax.lax.cond(any_over_agents(truncated, shared),
                                       lambda: bootstrap(runner.params, final_obs, runner.game),
                                       lambda: jnp.zeros(runner.obs.shape[0], jnp.float32))
            done = terminated | truncated
            episode_return = runner.episode_return + reward
            transition = Transition(runner.obs, legal, action, policy_out,
                                    reward + config.gamma * jnp.where(truncated, final_value, 0.0),
                                    done, jnp.where(done, episode_return, 0.0))
            runner = runner._replace(env_state=env_state, obs=obs, key=key,
                                     episode_return=jnp.where(done, 0.0, episode_return))
            return runner, transition

        return jax.lax.scan(env_step, runner, None, config.num_steps)

    return rollout


def make_learn(config: TrainConfig, optimizer: optax.GradientTransformation, loss: Callable) -> Callable:
    """`learn(runner, batch) -> (runner, stats)`: `config.update_epochs` passes over one rollout's
    `batch` (a pytree of (num_steps, lanes, ...) arrays: `config.batch_size` samples, self-play's
    twice as many), each a shuffle and a `lax.scan` of `config.num_minibatches` optimizer steps on
    `loss(params, minibatch) -> (loss, stats)`.

    Returns the runner with its new params, optimizer state and key and the update counted, and
    each of the loss's stats averaged over every minibatch step.
    """
    def sgd_step(carry, minibatch):
        params, opt_state = carry
        grads, stats = jax.grad(loss, has_aux=True)(params, minibatch)
        updates, opt_state = optimizer.update(grads, opt_state, params)
        return (optax.apply_updates(params, updates), opt_state), stats

    def epoch(carry, batch):
        params, opt_state, key = carry
        key, perm_key = jax.random.split(key)
        perm = jax.random.permutation(perm_key, jax.tree.leaves(batch)[0].shape[0])
        minibatches = jax.tree.map(lambda x: x[perm].reshape((config.num_minibatches, -1) + x.shape[1:]), batch)
        (params, opt_state), stats = jax.lax.scan(sgd_step, (params, opt_state), minibatches)
        return (params, opt_state, key), stats

    def learn(runner: RunnerState, batch):
        batch = jax.tree.map(lambda x: x.reshape((x.shape[0] * x.shape[1],) + x.shape[2:]), batch)
        (params, opt_state, key), stats = jax.lax.scan(
            lambda carry, _: epoch(carry, batch), (runner.params, runner.opt_state, runner.key),
            None, config.update_epochs)
        runner = runner._replace(params=params, opt_state=opt_state, key=key, updates=runner.updates + 1)
        return runner, {name: value.mean() for name, value in stats.items()}

    return learn


def episode_totals(traj: Transition) -> dict[str, jax.Array]:
    """The rollout's finished training episodes, as the log reads them: their number and the sum of their returns."""
    return {"finished_return_sum": traj.finished_return.sum(), "finished_episodes": traj.done.sum()}
