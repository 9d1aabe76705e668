"""What one update of the pure-JAX PPO and PQN examples shares: the runner, the rollout and the
minibatch epochs. Each example brings only its own parts: how it acts and what it keeps of each
step, the value it bootstraps from, its targets and its loss.

An update of either algorithm is

    runner, traj = rollout(runner, act_arg)        # num_steps vmapped env steps under lax.scan
    batch = <the algorithm's targets from traj>    # PPO: GAE; PQN: Q(lambda) returns
    runner, stats = learn(runner, batch)           # update_epochs shuffled passes of minibatch steps

with `rollout` from `make_rollout` and `learn` from `make_learn`. Everything here is a pure
function of one agent; `jax_training.train` maps it over seeds.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import optax

import octax_core
from jax_training import RunConfig, any_over_seeds


class RunnerState(NamedTuple):
    """One agent between updates: its network and optimizer, its envs mid-episode, its key."""

    params: Any
    opt_state: Any
    env_state: Any  # batched octax_core.EnvState, (num_envs, ...)
    obs: jax.Array  # (num_envs, F, 32, 64) uint8
    episode_return: jax.Array  # (num_envs,) float32, return so far of each running episode
    key: jax.Array
    updates: jax.Array  # () int32: updates done, for schedules (PQN's epsilon)


class Transition(NamedTuple):
    """One step of the envs; a rollout stacks `num_steps` of them, each field (num_steps, num_envs, ...)."""

    obs: jax.Array  # (num_envs, F, 32, 64) uint8: what the policy saw
    action: jax.Array  # (num_envs,) int32
    policy_out: Any  # what `act` kept besides the action: PPO's log-prob and value, PQN's max Q
    reward: jax.Array  # (num_envs,) float32, plus gamma * bootstrap(final obs) where truncated
    done: jax.Array  # (num_envs,) bool, terminated | truncated: targets do not look past it
    finished_return: jax.Array  # (num_envs,) float32: the episode's return where it ended this step, else 0


def make_optimizer(config: RunConfig) -> optax.GradientTransformation:
    """Adam after global-norm clipping; the rate decays linearly to 0 with `anneal_lr`."""
    lr = config.learning_rate
    if config.anneal_lr:
        lr = optax.linear_schedule(lr, 0.0, config.num_updates * config.update_epochs * config.num_minibatches)
    return optax.chain(optax.clip_by_global_norm(config.max_grad_norm), optax.adam(lr))


def make_init(config: RunConfig, env: octax_core.Env, env_params: octax_core.EnvParams, network,
              optimizer: optax.GradientTransformation) -> Callable:
    """`init(key) -> RunnerState`: fresh network params (flax `network`), optimizer state and
    `config.num_envs` envs just reset."""
    v_reset = jax.vmap(env.reset, in_axes=(0, None))
    n = config.num_envs

    def init(key: jax.Array) -> RunnerState:
        key, net_key, env_key = jax.random.split(key, 3)
        obs, env_state = v_reset(jax.random.split(env_key, n), env_params)
        params = network.init(net_key, obs[:1])
        return RunnerState(params, optimizer.init(params), env_state, obs, jnp.zeros(n, jnp.float32), key,
                           jnp.int32(0))

    return init


def make_rollout(config: RunConfig, env: octax_core.Env, env_params: octax_core.EnvParams,
                 act: Callable, bootstrap: Callable) -> Callable:
    """`rollout(runner, act_arg) -> (runner, traj)`: `config.num_steps` steps of the batched env
    under `lax.scan`, `traj` a `Transition` of (num_steps, num_envs, ...) arrays.

    Args:
      env: made with `autoreset=True`: the scan runs straight over episode ends.
      act: `(params, key, obs, act_arg) -> (action, policy_out)`, the behaviour policy on a batch
        of observations; `policy_out` (any pytree of (num_envs, ...) arrays) is kept in the
        transition for the targets and the loss. `act_arg` is what the policy takes per rollout
        (PQN's epsilon; PPO's is None).
      bootstrap: `(params, obs) -> (num_envs,)` value of observations (PPO's critic, PQN's max Q),
        credited to a truncated episode's last reward.

    Raises:
      ValueError: `env` does not reset itself.
    """
    if not env.config.autoreset:
        raise ValueError("make_rollout needs an env made with autoreset=True (it scans over episode ends)")
    v_step = jax.vmap(env.step, in_axes=(0, 0, 0, None))
    n = config.num_envs

    def rollout(runner: RunnerState, act_arg=None):
        def env_step(runner: RunnerState, _):
            key, action_key, step_key = jax.random.split(runner.key, 3)
            action, policy_out = act(runner.params, action_key, runner.obs, act_arg)
            obs, env_state, reward, terminated, truncated, info = v_step(
                jax.random.split(step_key, n), runner.env_state, action, env_params)
            # Partial-episode bootstrapping: a time limit is not a terminal state, so a truncated
            # episode is credited gamma * value(its last observation). Rare, so the network runs only then.
            final_value = jax.lax.cond(any_over_seeds(truncated, config.num_seeds),
                                       lambda: bootstrap(runner.params, info["final_observation"]),
                                       lambda: jnp.zeros(n, jnp.float32))
            done = terminated | truncated
            episode_return = runner.episode_return + reward
            transition = Transition(runner.obs, action, policy_out,
                                    reward + config.gamma * jnp.where(truncated, final_value, 0.0),
                                    done, jnp.where(done, episode_return, 0.0))
            runner = runner._replace(env_state=env_state, obs=obs, key=key,
                                     episode_return=jnp.where(done, 0.0, episode_return))
            return runner, transition

        return jax.lax.scan(env_step, runner, None, config.num_steps)

    return rollout


def make_learn(config: RunConfig, optimizer: optax.GradientTransformation, loss: Callable) -> Callable:
    """`learn(runner, batch) -> (runner, stats)`: `config.update_epochs` passes over one rollout's
    `batch` (a pytree of (num_steps, num_envs, ...) arrays), each a shuffle and a `lax.scan` of
    `config.num_minibatches` optimizer steps on `loss(params, minibatch) -> (loss, stats)`.

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
        perm = jax.random.permutation(perm_key, config.batch_size)
        minibatches = jax.tree.map(
            lambda x: x[perm].reshape((config.num_minibatches, -1) + x.shape[1:]), batch)
        (params, opt_state), stats = jax.lax.scan(sgd_step, (params, opt_state), minibatches)
        return (params, opt_state, key), stats

    def learn(runner: RunnerState, batch):
        batch = jax.tree.map(lambda x: x.reshape((config.batch_size,) + x.shape[2:]), batch)
        (params, opt_state, key), stats = jax.lax.scan(
            lambda carry, _: epoch(carry, batch), (runner.params, runner.opt_state, runner.key),
            None, config.update_epochs)
        runner = runner._replace(params=params, opt_state=opt_state, key=key, updates=runner.updates + 1)
        return runner, {name: value.mean() for name, value in stats.items()}

    return learn


def episode_totals(traj: Transition) -> dict[str, jax.Array]:
    """The rollout's finished training episodes, as `jax_training.RunLog` reads them: their number
    and the sum of their returns."""
    return {"finished_return_sum": traj.finished_return.sum(), "finished_episodes": traj.done.sum()}
