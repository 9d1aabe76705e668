"""PPO (clipped, with GAE): how it acts, its targets and its loss, over rollout.py's update.

The paper's settings are `presets.PAPER["ppo"]`: 512 envs, 32-step rollouts, 4 epochs of 32
minibatches, Adam 5e-4, GAE 0.95, clip 0.2 (the value loss clipped too, as CleanRL's Atari PPO
and the paper's Rejax-based code do), value 0.5, entropy 0.01, gamma 0.99, grad norm 0.5. Logits
are masked to the agent's game's actions (networks.masked) before every sample, log-prob,
entropy and argmax, so an action the game does not take is never drawn and costs no entropy.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from octax_gym.train import rollout as shared
from octax_gym.train.algorithm import Trainer
from octax_gym.train.config import TrainConfig
from octax_gym.train.envs import Lanes
from octax_gym.train.networks import ActorCritic, masked

METRICS = ("pg_loss", "v_loss", "entropy", "approx_kl", "clip_frac", "learning_rate")


class OldPolicy(NamedTuple):
    """What the rollout's policy said at each step, kept for the ratio and the value clip."""

    log_prob: jax.Array  # (num_envs,) float32, of the action taken
    value: jax.Array  # (num_envs,) float32, the critic's


def make_trainer(config: TrainConfig, lanes: Lanes) -> Trainer:
    """PPO for the run's lanes: a `Trainer` of one agent (the loop maps it over agents and compiles it).

    `config.multitask`: one agent over all the games, its lanes' games (and with `game_input` the
    game's one-hot, `ActorCritic(num_games=G)`) read per lane; otherwise one agent, one game.
    """
    num_games = len(lanes.games) if config.multitask and config.game_input else 0
    network, optimizer = ActorCritic(num_games=num_games), shared.make_optimizer(config)
    legal_of = jnp.asarray(lanes.legal)

    def net_input(obs, game):
        return (obs, jnp.broadcast_to(game, obs.shape[:1])) if num_games else obs

    def apply(params, obs, game):
        logits, value = network.apply(params, net_input(obs, game))
        return masked(logits, legal_of[game]), value

    def act(params, key, obs, game, _):
        logits, value = apply(params, obs, game)
        action = jax.random.categorical(key, logits)
        log_prob = jnp.take_along_axis(jax.nn.log_softmax(logits), action[:, None], 1)[:, 0]
        return action, OldPolicy(log_prob, value)

    def critic(params, obs, game):
        return apply(params, obs, game)[1]

    rollout = shared.make_rollout(config, lanes, act, critic)
    learn = shared.make_learn(config, optimizer, lambda params, minibatch: ppo_loss(params, apply, config, minibatch))

    def collect(runner: shared.RunnerState):
        runner, traj = rollout(runner)
        old = traj.policy_out
        last_value = critic(runner.params, runner.obs, runner.game)
        advantages, targets = gae(traj.reward, traj.done, old.value, last_value, config.gamma, config.gae_lambda)
        games = jnp.broadcast_to(runner.game, traj.action.shape)  # each sample's game: its mask (and input)
        batch = (traj.obs, games, traj.action, old.log_prob, old.value, advantages, targets)
        return runner, batch, shared.episode_totals(traj)

    def greedy(params, key, obs, game):
        return jnp.argmax(apply(params, obs, game)[0], axis=1).astype(jnp.int32)

    def sampled(params, key, obs, game):
        return jax.random.categorical(key, apply(params, obs, game)[0]).astype(jnp.int32)

    return Trainer("PPO", network, shared.make_init(config, lanes, network, optimizer, net_input), collect, learn,
                   greedy, sampled, METRICS, lambda i: {"learning_rate": config.learning_rate_at(i)})


def gae(reward: jax.Array, done: jax.Array, value: jax.Array, last_value: jax.Array, gamma: float, lam: float):
    """Generalized advantage estimates and value targets, both (num_steps, num_envs) as the inputs;
    `last_value` (num_envs,) is the critic's after the last step."""
    def backward(carry, step):
        advantage, next_value = carry
        reward, done, value = step
        not_done = 1.0 - done.astype(jnp.float32)
        delta = reward + gamma * next_value * not_done - value
        advantage = delta + gamma * lam * not_done * advantage
        return (advantage, value), advantage

    _, advantages = jax.lax.scan(backward, (jnp.zeros_like(last_value), last_value), (reward, done, value),
                                 reverse=True)
    return advantages, advantages + value


def ppo_loss(params, apply, config: TrainConfig, minibatch):
    """The clipped surrogate, the (clipped) value loss and the entropy bonus, over masked logits
    (`apply(params, obs, game) -> (masked logits, values)`)."""
    obs, game, action, old_log_prob, old_value, advantage, target = minibatch
    logits, value = apply(params, obs, game)
    log_probs = jax.nn.log_softmax(logits)
    log_prob = jnp.take_along_axis(log_probs, action[:, None], 1)[:, 0]
    entropy = -(jnp.exp(log_probs) * log_probs).sum(-1).mean()
    log_ratio = log_prob - old_log_prob
    ratio = jnp.exp(log_ratio)
    advantage = (advantage - advantage.mean()) / (advantage.std() + 1e-8)
    clipped = jnp.clip(ratio, 1 - config.clip_eps, 1 + config.clip_eps)
    pg_loss = -jnp.minimum(ratio * advantage, clipped * advantage).mean()
    v_loss = jnp.square(value - target)
    if config.clip_value_loss:
        v_clipped = old_value + jnp.clip(value - old_value, -config.clip_eps, config.clip_eps)
        v_loss = jnp.maximum(v_loss, jnp.square(v_clipped - target))
    v_loss = 0.5 * v_loss.mean()
    loss = pg_loss + config.vf_coef * v_loss - config.ent_coef * entropy
    stats = {"pg_loss": pg_loss, "v_loss": v_loss, "entropy": entropy,
             "approx_kl": ((ratio - 1) - log_ratio).mean(),
             "clip_frac": (jnp.abs(ratio - 1) > config.clip_eps).mean()}
    return loss, stats
