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
`update_epochs` x `num_minibatches` Adam steps, all in one compiled call. Every `--eval-every`
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
from pathlib import Path
from typing import Any, Callable, NamedTuple, Optional, Sequence

import jax
import jax.numpy as jnp
import optax

import octax_core
import jax_training
from jax_networks import ActorCritic, Conv, ConvTorso, conv_valid  # noqa: F401  (the example's network)
from jax_training import RunConfig, Trainer, make_envs, make_evaluate, make_optimizer, random_act  # noqa: F401

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

class RunnerState(NamedTuple):
    params: Any
    opt_state: Any
    env_state: Any  # batched octax_core.EnvState
    obs: jax.Array  # (num_envs, F, 32, 64) uint8
    episode_return: jax.Array  # (num_envs,) float32, return so far of each running episode
    key: jax.Array


class Transition(NamedTuple):
    obs: jax.Array
    action: jax.Array
    log_prob: jax.Array
    value: jax.Array
    reward: jax.Array  # plus gamma * V(final obs) where the episode was truncated
    done: jax.Array  # terminated | truncated: GAE does not look past it
    finished_return: jax.Array  # the episode's return where it ended this step, else 0


def make_train(config: Config, env: octax_core.Env, env_params: octax_core.EnvParams) -> Trainer:
    """PPO for `env` (made with `autoreset=True`): a `Trainer` of one agent; jit `update` yourself
    (`jax_training.train` maps it over seeds and compiles it)."""
    if not env.config.autoreset:
        raise ValueError("make_train needs an env made with autoreset=True (it scans over episode ends)")
    config.check()
    network, optimizer = ActorCritic(env.num_actions), make_optimizer(config)
    v_reset = jax.vmap(env.reset, in_axes=(0, None))
    v_step = jax.vmap(env.step, in_axes=(0, 0, 0, None))
    n = config.num_envs

    def init(key: jax.Array) -> RunnerState:
        key, net_key, env_key = jax.random.split(key, 3)
        obs, env_state = v_reset(jax.random.split(env_key, n), env_params)
        params = network.init(net_key, obs[:1])
        return RunnerState(params, optimizer.init(params), env_state, obs, jnp.zeros(n, jnp.float32), key)

    def env_step(runner: RunnerState, _):
        key, action_key, step_key = jax.random.split(runner.key, 3)
        logits, value = network.apply(runner.params, runner.obs)
        action = jax.random.categorical(action_key, logits)
        log_prob = jnp.take_along_axis(jax.nn.log_softmax(logits), action[:, None], 1)[:, 0]
        obs, env_state, reward, terminated, truncated, info = v_step(
            jax.random.split(step_key, n), runner.env_state, action, env_params)
        # Partial-episode bootstrapping: a time limit is not a terminal state, so a truncated
        # episode is credited gamma * V(its last observation). Rare, so the critic runs only then.
        final_value = jax.lax.cond(jax_training.any_over_seeds(truncated, config.num_seeds),
                                   lambda: network.apply(runner.params, info["final_observation"])[1],
                                   lambda: jnp.zeros(n, jnp.float32))
        done = terminated | truncated
        episode_return = runner.episode_return + reward
        transition = Transition(runner.obs, action, log_prob, value,
                                reward + config.gamma * jnp.where(truncated, final_value, 0.0),
                                done, jnp.where(done, episode_return, 0.0))
        runner = runner._replace(env_state=env_state, obs=obs, key=key,
                                 episode_return=jnp.where(done, 0.0, episode_return))
        return runner, transition

    def update(runner: RunnerState):
        runner, traj = jax.lax.scan(env_step, runner, None, config.num_steps)
        last_value = network.apply(runner.params, runner.obs)[1]
        advantages, targets = _gae(traj, last_value, config.gamma, config.gae_lambda)
        batch = (traj.obs, traj.action, traj.log_prob, traj.value, advantages, targets)
        batch = jax.tree.map(lambda x: x.reshape((config.batch_size,) + x.shape[2:]), batch)
        params, opt_state, key, stats = jax_training.run_epochs(
            config, sgd_step, batch, runner.params, runner.opt_state, runner.key)
        metrics = {k: v.mean() for k, v in stats.items()}
        metrics["finished_return_sum"] = traj.finished_return.sum()
        metrics["finished_episodes"] = traj.done.sum()
        return runner._replace(params=params, opt_state=opt_state, key=key), metrics

    def sgd_step(carry, minibatch):
        params, opt_state = carry
        grads, stats = jax.grad(_ppo_loss, has_aux=True)(params, network, config, minibatch)
        updates, opt_state = optimizer.update(grads, opt_state, params)
        return (optax.apply_updates(params, updates), opt_state), stats

    return Trainer("PPO", network, init, update, policy_act(network), lambda runner: runner.params,
                   METRICS, lambda i: {"learning_rate": config.learning_rate_at(i)})


def _gae(traj: Transition, last_value: jax.Array, gamma: float, lam: float):
    """Generalized advantage estimates and value targets, both (num_steps, num_envs)."""
    def backward(carry, t):
        advantage, next_value = carry
        not_done = 1.0 - t.done.astype(jnp.float32)
        delta = t.reward + gamma * next_value * not_done - t.value
        advantage = delta + gamma * lam * not_done * advantage
        return (advantage, t.value), advantage

    _, advantages = jax.lax.scan(backward, (jnp.zeros_like(last_value), last_value), traj, reverse=True)
    return advantages, advantages + traj.value


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


def parse_args(argv: Optional[Sequence[str]] = None) -> tuple[Config, Path]:
    return jax_training.parse_args(Config, HELP, __doc__.split("\n\n")[0], "runs/jax_ppo", argv)


def main(argv: Optional[Sequence[str]] = None) -> dict:
    config, out_dir = parse_args(argv)
    print(f"PPO on {config.game}: {config}")
    summary = train(config, out_dir)
    print(f"wrote {summary['csv']} and {summary['png']}")
    return summary


if __name__ == "__main__":
    main(sys.argv[1:])
