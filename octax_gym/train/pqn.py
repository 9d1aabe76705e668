"""PQN (Gallici et al., 2024): epsilon-greedy acting, Q(lambda) targets and the TD loss, over
rollout.py's update.

Q-learning without a replay buffer or target network: many parallel envs collect a short
on-policy rollout epsilon-greedily, Q(lambda) returns are computed backwards over it, and a few
epochs of minibatch regression follow, as PPO's epochs do; LayerNorm in the network keeps it
stable. The paper's settings are `presets.PAPER["pqn"]`. Q-values of actions the agent's game
does not take are masked (networks.masked) before every max and argmax, and exploration draws
among the game's own actions only.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from octax_gym.train import rollout as shared
from octax_gym.train.algorithm import Trainer
from octax_gym.train.config import TrainConfig
from octax_gym.train.envs import Lanes
from octax_gym.train.networks import QNetwork, masked

METRICS = ("td_loss", "q_mean", "target_mean", "epsilon", "learning_rate")


def epsilon_greedy(q_values: jax.Array, key: jax.Array, epsilon, legal: jax.Array) -> jax.Array:
    """argmax of the legal Q-values, or with probability epsilon a uniformly drawn legal action, per
    row; `legal` (A,) or a row per Q-value row, a game's first actions (`Lanes.legal_mask`)."""
    explore_key, action_key = jax.random.split(key)
    count = legal.sum(-1)  # the game's actions are its first `count` (per row: the same draws as one count)
    random_action = jax.random.randint(action_key, q_values.shape[:1], 0, count)
    explore = jax.random.uniform(explore_key, q_values.shape[:1]) < epsilon
    return jnp.where(explore, random_action, jnp.argmax(masked(q_values, legal), axis=1)).astype(jnp.int32)


def make_trainer(config: TrainConfig, lanes: Lanes) -> Trainer:
    """PQN for the run's lanes: a `Trainer` of one agent (the loop maps it over agents and compiles it)."""
    network, optimizer = QNetwork(layout=config.network_layout), shared.make_optimizer(config)
    legal_of = jnp.asarray(lanes.legal)

    def explore(params, key, obs, game, legal, epsilon):
        q_values = network.apply(params, obs)
        return epsilon_greedy(q_values, key, epsilon, legal), masked(q_values, legal).max(axis=1)

    def max_q(params, obs, game):
        return masked(network.apply(params, obs), legal_of[game]).max(axis=1)

    rollout = shared.make_rollout(config, lanes, explore, max_q)
    learn = shared.make_learn(config, optimizer, lambda params, minibatch: td_loss(params, network, minibatch))

    def collect(runner: shared.RunnerState):
        epsilon = config.epsilon(runner.updates)
        runner, traj = rollout(runner, epsilon)
        targets = q_lambda_targets(traj.reward, traj.done, traj.policy_out, max_q(runner.params, runner.obs, runner.game),
                                   config.gamma, config.q_lambda)
        metrics = {"target_mean": targets.mean(), "epsilon": epsilon, **shared.episode_totals(traj)}
        return runner, (traj.obs, traj.action, targets), metrics

    def greedy(params, key, obs, game):
        return jnp.argmax(masked(network.apply(params, obs), legal_of[game]), axis=1).astype(jnp.int32)

    def sampled(params, key, obs, game):
        return epsilon_greedy(network.apply(params, obs), key, config.eval_epsilon, legal_of[game])

    return Trainer("PQN", network, shared.make_init(config, lanes, network, optimizer), collect, learn, greedy,
                   sampled, METRICS, lambda i: {"learning_rate": config.learning_rate_at(i), "epsilon": float(config.epsilon(i))})


def q_lambda_targets(reward: jax.Array, done: jax.Array, q_max: jax.Array, last_q: jax.Array, gamma: float,
                     lam: float) -> jax.Array:
    """Q(lambda) returns, (num_steps, num_envs) as the inputs, computed backwards over the rollout:

        G_t = r_t + gamma * (1 - done_t) * (lam * G_{t+1} + (1 - lam) * max_a Q(s_{t+1}, a))

    with G_T = max_a Q(s_T, a) after the last step (`last_q`, (num_envs,)), so lam = 0 is one-step
    Q-learning and lam = 1 the discounted return bootstrapped at the rollout's end. `q_max[t + 1]`
    is max_a Q(s_{t+1}, a); where step t ended an episode, s_{t+1} is the next episode's start and
    (1 - done_t) cuts it off.
    """
    def backward(carry, step):
        next_return, next_q_max = carry
        reward, done, q_max = step
        not_done = 1.0 - done.astype(jnp.float32)
        target = reward + gamma * not_done * (lam * next_return + (1.0 - lam) * next_q_max)
        return (target, q_max), target

    _, targets = jax.lax.scan(backward, (last_q, last_q), (reward, done, q_max), reverse=True)
    return targets


def td_loss(params, network: QNetwork, minibatch):
    """Half the squared error of the taken actions' Q-values against the (fixed) Q(lambda) targets."""
    obs, action, target = minibatch
    q_values = network.apply(params, obs)
    q_taken = jnp.take_along_axis(q_values, action[:, None], 1)[:, 0]
    loss = 0.5 * jnp.square(q_taken - jax.lax.stop_gradient(target)).mean()
    return loss, {"td_loss": loss, "q_mean": q_taken.mean()}
