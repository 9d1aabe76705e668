"""PPO (clipped, with GAE): how it acts, its targets and its loss, over rollout.py's update.

The paper's settings are `presets.PAPER["ppo"]`: 512 envs, 32-step rollouts, 4 epochs of 32
minibatches, Adam 5e-4, GAE 0.95, clip 0.2 (the value loss clipped too, as CleanRL's Atari PPO
and the paper's Rejax-based code do), value 0.5, entropy 0.01, gamma 0.99, grad norm 0.5. Logits
are masked to the actions open to each lane (the lanes' `legal_mask`: a one-player game's own
actions; in a turn-based two-player game, only no-op for the seat not to move) before every
sample, log-prob, entropy and argmax, so a closed action is never drawn and costs no entropy.

Each sample carries a weight in the loss (`OldPolicy.weight`): 1 for the agent's own samples,
which is every sample of ppo and multitask runs and of self-play without a pool (their loss
takes the plain means, bit for bit those of the unweighted loss); 0 where self-play's pool put a
past self on the seat (selfplay.py): another policy made those actions, so they train nothing,
while the same env's other seat trains as usual.
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

    log_prob: jax.Array  # (lanes,) float32, of the action taken
    value: jax.Array  # (lanes,) float32, the critic's
    weight: jax.Array  # (lanes,) float32: 1 for the agent's own action, 0 for a past self's (self-play's pool)


def make_trainer(config: TrainConfig, lanes: Lanes) -> Trainer:
    """PPO for the run's lanes: a `Trainer` of one agent (the loop maps it over agents and compiles it).

    `config.multitask`: one agent over all the games, its lanes' games (and with `game_input` the
    game's one-hot, `ActorCritic(num_games=G)`) read per lane; otherwise one agent, one game.
    `config.selfplay`: one agent on both seats of `lanes` (seats.SeatLanes), its pool of past
    selves (selfplay.py) drawn before each rollout and playing the seats it picks.
    """
    num_games = len(lanes.games) if config.multitask and config.game_input else 0
    network, optimizer = ActorCritic(num_games=num_games, layout=config.network_layout), shared.make_optimizer(config)
    legal_of = jnp.asarray(lanes.legal)

    def net_input(obs, game):
        return (obs, jnp.broadcast_to(game, obs.shape[:1])) if num_games else obs

    def apply(params, obs, game, legal):
        logits, value = network.apply(params, net_input(obs, game))
        return masked(logits, legal), value

    def act(params, key, obs, game, legal, opponent):
        logits, value = apply(params, obs, game, legal)
        action = jax.random.categorical(key, logits)
        weight = jnp.ones(action.shape, jnp.float32)
        if opponent is not None:  # self-play's pool: a past self's action on the lanes it plays, weight 0
            past_params, past = opponent
            past_action = jax.random.categorical(jax.random.fold_in(key, 1), apply(past_params, obs, game, legal)[0])
            action, weight = jnp.where(past, past_action, action), jnp.where(past, 0.0, weight)
        log_prob = jnp.take_along_axis(jax.nn.log_softmax(logits), action[:, None], 1)[:, 0]
        return action, OldPolicy(log_prob, value, weight)

    def critic(params, obs, game):
        return network.apply(params, net_input(obs, game))[1]

    rollout = shared.make_rollout(config, lanes, act, critic)
    learn = shared.make_learn(config, optimizer, lambda params, minibatch: ppo_loss(params, apply, config, minibatch))

    def collect(runner: shared.RunnerState):
        opponent = None
        if config.selfplay and config.pool:
            from octax_gym.train import selfplay

            runner, opponent = selfplay.draw_opponent(config, runner)
        runner, traj = rollout(runner, opponent)
        old = traj.policy_out
        last_value = critic(runner.params, runner.obs, runner.game)
        advantages, targets = gae(traj.reward, traj.done, old.value, last_value, config.gamma, config.gae_lambda)
        games = jnp.broadcast_to(runner.game, traj.action.shape)  # each sample's game: its input (multitask)
        batch = (traj.obs, games, traj.legal, traj.action, old.log_prob, old.value, advantages, targets, old.weight)
        if config.ent_coef_final is not None:  # this update's entropy weight, a column so the loss reads it
            batch += (jnp.full(traj.action.shape, config.ent_coef_at(runner.updates), jnp.float32),)
        return runner, batch, shared.episode_totals(traj)

    def greedy(params, key, obs, game):
        return jnp.argmax(apply(params, obs, game, legal_of[game])[0], axis=1).astype(jnp.int32)

    def sampled(params, key, obs, game):
        return jax.random.categorical(key, apply(params, obs, game, legal_of[game])[0]).astype(jnp.int32)

    init = shared.make_init(config, lanes, network, optimizer, net_input)
    if config.selfplay and config.pool:
        from octax_gym.train import selfplay

        init = selfplay.with_pool(config, init)
    annealed = config.ent_coef_final is not None
    return Trainer("PPO", network, init, collect, learn, greedy, sampled, METRICS + ("ent_coef",) * annealed,
                   lambda i: {"learning_rate": config.learning_rate_at(i),
                              **({"ent_coef": float(config.ent_coef_at(i))} if annealed else {})})


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
    """The clipped surrogate, the (clipped) value loss and the entropy bonus, over logits masked to
    each sample's legal actions (`apply(params, obs, game, legal) -> (masked logits, values)`),
    every mean (the advantages' normalisation too) weighted by the samples' weights. With
    `ent_coef_final` the minibatch ends with each sample's entropy weight (the update's, `ent_coef_at`);
    without it the batch is as it was and the weight `ent_coef`."""
    obs, game, legal, action, old_log_prob, old_value, advantage, target, weight, *scheduled = minibatch
    ent_coef = scheduled[0][0] if scheduled else config.ent_coef
    logits, value = apply(params, obs, game, legal)
    # Only a pool's past selves weigh 0: without one every weight is 1, and the plain means are
    # kept, so that ppo and multitask runs stay bit for bit what they were (the weighted form of
    # the same means differs in the last float bits, measured).
    weighted = config.selfplay and config.pool > 0
    total = jnp.maximum(weight.sum(), 1.0)  # a minibatch of past selves' samples alone trains nothing

    def mean(x):
        return (x * weight).sum() / total if weighted else x.mean()

    log_probs = jax.nn.log_softmax(logits)
    log_prob = jnp.take_along_axis(log_probs, action[:, None], 1)[:, 0]
    entropy = -mean((jnp.exp(log_probs) * log_probs).sum(-1))
    log_ratio = log_prob - old_log_prob
    ratio = jnp.exp(log_ratio)
    centred = advantage - mean(advantage)
    advantage = centred / ((jnp.sqrt(mean(jnp.square(centred))) if weighted else advantage.std()) + 1e-8)
    clipped = jnp.clip(ratio, 1 - config.clip_eps, 1 + config.clip_eps)
    pg_loss = -mean(jnp.minimum(ratio * advantage, clipped * advantage))
    v_loss = jnp.square(value - target)
    if config.clip_value_loss:
        v_clipped = old_value + jnp.clip(value - old_value, -config.clip_eps, config.clip_eps)
        v_loss = jnp.maximum(v_loss, jnp.square(v_clipped - target))
    v_loss = 0.5 * mean(v_loss)
    loss = pg_loss + config.vf_coef * v_loss - ent_coef * entropy
    stats = {"pg_loss": pg_loss, "v_loss": v_loss, "entropy": entropy,
             "approx_kl": mean((ratio - 1) - log_ratio),
             "clip_frac": mean(jnp.abs(ratio - 1) > config.clip_eps)}
    return loss, stats
