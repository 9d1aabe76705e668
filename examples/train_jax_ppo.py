"""PPO on an octax game, end to end in JAX: env steps, GAE and Adam updates in one jitted update.

    python examples/train_jax_ppo.py --game Airplane --num-envs 64 --num-minibatches 8 --total-steps 655360
    # 7-13 minutes on 2 CPU cores; the defaults (512 envs, 5M steps) are the paper's, for a GPU
    python examples/train_jax_ppo.py --game Airplane --num-seeds 3 ...   # 3 agents in one program

The defaults are the paper's (Octax, Radji et al.; 512 envs, 32-step rollouts, 4 epochs of 32
minibatches, Adam 5e-4, GAE 0.95, clip 0.2, vf 0.5, entropy 0.01, gamma 0.99, grad norm 0.5) and its
network (a CNN for the (4, 64, 32) frames, separate 256-unit actor and critic heads:
examples/jax_networks.py, shared with the PQN example). The learning
rate is constant (`--anneal-lr` decays it linearly to 0): the paper does not mention a schedule,
and its code (Rejax-based) passes a constant rate to Adam.

One update is `lax.scan` over `num_steps` vmapped env steps (same-step autoreset), GAE, then
`update_epochs` x `num_minibatches` Adam steps, all in one compiled call. The rollout and the
epochs are examples/jax_update.py's, shared with the PQN example; this file holds what is PPO's:
sampling from the actor, GAE and the clipped loss. Every `--eval-every`
env steps the current policy plays `--eval-envs` separate episodes to the end (actions sampled:
the policy is stochastic, as in the paper's evaluation), and a uniform-random policy is measured
the same way once at the start. `--num-seeds S` trains S independent agents (seeds seed ..
seed + S - 1) in one jitted program, vmapped over seeds (examples/jax_training.py). Writes
`progress.csv` (one row per seed and evaluation), `learning_curve.png` and the final params
(`params.msgpack`, or `params-seed<N>.msgpack` per seed; flax.serialization) to `--out-dir`.
See docs/training.md.
"""

from __future__ import annotations

import dataclasses
import sys
from typing import Callable, NamedTuple, Optional, Sequence

import jax
import jax.numpy as jnp

import octax_core
import jax_training
import jax_update
from jax_networks import ActorCritic, Conv, ConvTorso, conv_valid  # noqa: F401  (the example's network)
from jax_training import RunConfig, Trainer, make_envs, make_evaluate, random_act  # noqa: F401

METRICS = ("pg_loss", "v_loss", "entropy", "approx_kl", "clip_frac", "learning_rate")
CSV_COLUMNS = jax_training.COMMON_COLUMNS + METRICS


@dataclasses.dataclass(frozen=True)
class Config(RunConfig):
    """Everything a PPO run depends on; defaults are the paper's PPO settings."""

    gae_lambda: float = 0.95
    clip_eps: float = 0.2
    clip_value_loss: bool = True  # CleanRL's Atari PPO and the paper's Rejax-based code clip it
    vf_coef: float = 0.5
    ent_coef: float = 0.01


# --- training ---------------------------------------------------------------------------------

class OldPolicy(NamedTuple):
    """What the rollout's policy said at each step, kept for the ratio and the value clip."""

    log_prob: jax.Array  # (num_envs,) float32, of the action taken
    value: jax.Array  # (num_envs,) float32, the critic's


def make_train(config: Config, env: octax_core.Env, env_params: octax_core.EnvParams) -> Trainer:
    """PPO for `env` (made with `autoreset=True`): a `Trainer` of one agent; jit `update` yourself
    (`jax_training.train` maps it over seeds and compiles it)."""
    config.check()
    network, optimizer = ActorCritic(env.num_actions), jax_update.make_optimizer(config)

    def act(params, key, obs, _):
        logits, value = network.apply(params, obs)
        action = jax.random.categorical(key, logits)
        log_prob = jnp.take_along_axis(jax.nn.log_softmax(logits), action[:, None], 1)[:, 0]
        return action, OldPolicy(log_prob, value)

    def critic(params, obs):
        return network.apply(params, obs)[1]

    rollout = jax_update.make_rollout(config, env, env_params, act, critic)
    learn = jax_update.make_learn(config, optimizer, lambda params, minibatch: _ppo_loss(
        params, network, config, minibatch))

    def update(runner: jax_update.RunnerState):
        runner, traj = rollout(runner)
        old = traj.policy_out
        advantages, targets = _gae(traj.reward, traj.done, old.value, critic(runner.params, runner.obs),
                                   config.gamma, config.gae_lambda)
        runner, metrics = learn(runner, (traj.obs, traj.action, old.log_prob, old.value, advantages, targets))
        return runner, {**metrics, **jax_update.episode_totals(traj)}

    return Trainer("PPO", network, jax_update.make_init(config, env, env_params, network, optimizer), update,
                   policy_act(network), lambda runner: runner.params, METRICS,
                   lambda i: {"learning_rate": config.learning_rate_at(i)})


def _gae(reward: jax.Array, done: jax.Array, value: jax.Array, last_value: jax.Array, gamma: float,
         lam: float):
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


def _ppo_loss(params, network: ActorCritic, config: Config, minibatch):
    obs, action, old_log_prob, old_value, advantage, target = minibatch
    logits, value = network.apply(params, obs)
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


def policy_act(network: ActorCritic) -> Callable:
    """Samples from the policy: the stochastic policy is what is evaluated."""
    return lambda params, key, obs: jax.random.categorical(key, network.apply(params, obs)[0])


# --- the run ----------------------------------------------------------------------------------

def train(config: Config, out_dir, game=None, rom=None, progress: bool = True) -> dict:
    """Runs PPO for `config.num_seeds` seeds at once (`jax_training.train`); writes progress.csv,
    learning_curve.png and the params. Returns the summary (paths, speed, random and final returns)."""
    return jax_training.train(config, make_train, out_dir, game=game, rom=rom, progress=progress)


HELP = {
    "gae_lambda": "GAE lambda",
    "clip_eps": "PPO ratio clip (and value clip)",
    "clip_value_loss": "clip the value loss as CleanRL's Atari PPO does",
    "vf_coef": "value loss weight",
    "ent_coef": "entropy bonus weight",
}


def main(argv: Optional[Sequence[str]] = None) -> dict:
    """The command line (`jax_training.main`): flags, training, and the summary returned."""
    return jax_training.main("PPO", Config, make_train, HELP, __doc__, "runs/jax_ppo", argv)


if __name__ == "__main__":
    main(sys.argv[1:])
