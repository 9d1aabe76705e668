"""PQN on an octax game, end to end in JAX: env steps, Q(lambda) targets and Adam updates in one jitted update.

    python examples/train_jax_pqn.py --game Airplane --num-envs 64 --num-minibatches 8 --total-steps 655360
    # minutes on 2 CPU cores; the defaults (512 envs, 5M steps) are the paper's, for a GPU
    python examples/train_jax_pqn.py --game Airplane --num-seeds 3 ...   # 3 agents in one program

PQN (Gallici et al., 2024, "Simplifying Deep Temporal Difference Learning") is Q-learning without a
replay buffer or target network: many parallel envs collect a short on-policy rollout with an
epsilon-greedy policy, Q(lambda) returns are computed backwards over it, and a few epochs of
minibatch regression on them follow, as PPO's epochs do. LayerNorm in the network keeps it stable.

The defaults are the octax paper's (Radji et al., section 5): its network with LayerNorm
(examples/jax_networks.py, the torso shared with the PPO example), lambda 0.9, epsilon-greedy
decaying linearly from 1.0 to 0.05 over the first 10% of training, 512 envs x 32-step rollouts,
4 epochs of 32 minibatches, Adam 5e-4 with gradient clipping (global norm 10, PQN's own
setting: the paper gives no value), gamma 0.99, constant learning rate. Evaluation plays the
epsilon-greedy policy with epsilon 0.005 (the paper's code evaluates with it).

Same command line, progress bar, CSV and learning curve as the PPO example (examples/jax_training.py),
`--num-seeds S` included. See docs/training.md.
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
from jax_networks import QNetwork
from jax_training import RunConfig, Trainer, make_envs, make_evaluate, make_optimizer, random_act  # noqa: F401

METRICS = ("td_loss", "q_mean", "target_mean", "epsilon", "learning_rate")
CSV_COLUMNS = jax_training.COMMON_COLUMNS + METRICS


@dataclasses.dataclass(frozen=True)
class Config(RunConfig):
    """Everything a PQN run depends on; defaults are the paper's PQN settings."""

    max_grad_norm: float = 10.0
    q_lambda: float = 0.9
    epsilon_start: float = 1.0
    epsilon_finish: float = 0.05
    epsilon_fraction: float = 0.1  # of total_steps, over which epsilon decays linearly
    eval_epsilon: float = 0.005

    def epsilon(self, update: Any) -> Any:
        """Exploration rate of the rollout of update number `update` (from 0): linear in the env
        steps done before it, from epsilon_start to epsilon_finish at epsilon_fraction of the run."""
        decay_steps = max(1.0, self.epsilon_fraction * self.num_updates * self.batch_size)
        progress = jnp.minimum(1.0, jnp.asarray(update, jnp.float32) * self.batch_size / decay_steps)
        return self.epsilon_start + (self.epsilon_finish - self.epsilon_start) * progress


class RunnerState(NamedTuple):
    params: Any
    opt_state: Any
    env_state: Any  # batched octax_core.EnvState
    obs: jax.Array  # (num_envs, F, 32, 64) uint8
    episode_return: jax.Array  # (num_envs,) float32, return so far of each running episode
    key: jax.Array
    updates: jax.Array  # int32: updates done, for the epsilon schedule


class Transition(NamedTuple):
    obs: jax.Array
    action: jax.Array
    q_max: jax.Array  # max_a Q(obs, a) under the rollout's params: the bootstrap of the step before
    reward: jax.Array  # plus gamma * max_a Q(final obs, a) where the episode was truncated
    done: jax.Array  # terminated | truncated: the returns do not look past it
    finished_return: jax.Array  # the episode's return where it ended this step, else 0


def epsilon_greedy(q_values: jax.Array, key: jax.Array, epsilon) -> jax.Array:
    """argmax Q, or with probability epsilon a uniformly random action, per row."""
    explore_key, action_key = jax.random.split(key)
    random_action = jax.random.randint(action_key, q_values.shape[:1], 0, q_values.shape[1])
    explore = jax.random.uniform(explore_key, q_values.shape[:1]) < epsilon
    return jnp.where(explore, random_action, jnp.argmax(q_values, axis=1))


def make_train(config: Config, env: octax_core.Env, env_params: octax_core.EnvParams) -> Trainer:
    """PQN for `env` (made with `autoreset=True`): a `Trainer` of one agent; jit `update` yourself
    (`jax_training.train` maps it over seeds and compiles it)."""
    if not env.config.autoreset:
        raise ValueError("make_train needs an env made with autoreset=True (it scans over episode ends)")
    config.check()
    network, optimizer = QNetwork(env.num_actions), make_optimizer(config)
    v_reset = jax.vmap(env.reset, in_axes=(0, None))
    v_step = jax.vmap(env.step, in_axes=(0, 0, 0, None))
    n = config.num_envs

    def init(key: jax.Array) -> RunnerState:
        key, net_key, env_key = jax.random.split(key, 3)
        obs, env_state = v_reset(jax.random.split(env_key, n), env_params)
        params = network.init(net_key, obs[:1])
        return RunnerState(params, optimizer.init(params), env_state, obs, jnp.zeros(n, jnp.float32), key,
                           jnp.int32(0))

    def env_step(carry, _):
        runner, epsilon = carry
        key, action_key, step_key = jax.random.split(runner.key, 3)
        q_values = network.apply(runner.params, runner.obs)
        action = epsilon_greedy(q_values, action_key, epsilon)
        obs, env_state, reward, terminated, truncated, info = v_step(
            jax.random.split(step_key, n), runner.env_state, action, env_params)
        # A time limit is not a terminal state: a truncated episode is credited gamma * max Q of its
        # last observation. Rare, so the network runs on it only then.
        final_q = jax.lax.cond(jax_training.any_over_seeds(truncated, config.num_seeds),
                               lambda: network.apply(runner.params, info["final_observation"]).max(axis=1),
                               lambda: jnp.zeros(n, jnp.float32))
        done = terminated | truncated
        episode_return = runner.episode_return + reward
        transition = Transition(runner.obs, action, q_values.max(axis=1),
                                reward + config.gamma * jnp.where(truncated, final_q, 0.0),
                                done, jnp.where(done, episode_return, 0.0))
        runner = runner._replace(env_state=env_state, obs=obs, key=key,
                                 episode_return=jnp.where(done, 0.0, episode_return))
        return (runner, epsilon), transition

    def update(runner: RunnerState):
        epsilon = config.epsilon(runner.updates)
        (runner, _), traj = jax.lax.scan(env_step, (runner, epsilon), None, config.num_steps)
        last_q = network.apply(runner.params, runner.obs).max(axis=1)
        targets = q_lambda_targets(traj, last_q, config.gamma, config.q_lambda)
        batch = (traj.obs, traj.action, targets)
        batch = jax.tree.map(lambda x: x.reshape((config.batch_size,) + x.shape[2:]), batch)
        params, opt_state, key, stats = jax_training.run_epochs(
            config, sgd_step, batch, runner.params, runner.opt_state, runner.key)
        metrics = {k: v.mean() for k, v in stats.items()}
        metrics["target_mean"] = targets.mean()
        metrics["epsilon"] = epsilon
        metrics["finished_return_sum"] = traj.finished_return.sum()
        metrics["finished_episodes"] = traj.done.sum()
        runner = runner._replace(params=params, opt_state=opt_state, key=key, updates=runner.updates + 1)
        return runner, metrics

    def sgd_step(carry, minibatch):
        params, opt_state = carry
        grads, stats = jax.grad(_td_loss, has_aux=True)(params, network, minibatch)
        updates, opt_state = optimizer.update(grads, opt_state, params)
        return (optax.apply_updates(params, updates), opt_state), stats

    def act(params, key, obs):
        return epsilon_greedy(network.apply(params, obs), key, config.eval_epsilon)

    return Trainer("PQN", network, init, update, act, lambda runner: runner.params, METRICS,
                   lambda i: {"learning_rate": config.learning_rate_at(i), "epsilon": float(config.epsilon(i))})


def q_lambda_targets(traj: Transition, last_q: jax.Array, gamma: float, lam: float) -> jax.Array:
    """Q(lambda) returns, (num_steps, num_envs), computed backwards over the rollout:

        G_t = r_t + gamma * (1 - done_t) * (lam * G_{t+1} + (1 - lam) * max_a Q(s_{t+1}, a))

    with G_T = max_a Q(s_T, a) after the last step, so lam = 0 is one-step Q-learning and lam = 1
    the discounted return bootstrapped at the rollout's end. `traj.q_max[t + 1]` is
    max_a Q(s_{t+1}, a); where step t ended an episode, s_{t+1} is the next episode's start and
    (1 - done_t) cuts it off.
    """
    def backward(carry, t):
        next_return, next_q_max = carry
        not_done = 1.0 - t.done.astype(jnp.float32)
        target = t.reward + gamma * not_done * (lam * next_return + (1.0 - lam) * next_q_max)
        return (target, t.q_max), target

    _, targets = jax.lax.scan(backward, (last_q, last_q), traj, reverse=True)
    return targets


def _td_loss(params, network: QNetwork, minibatch):
    obs, action, target = minibatch
    q_values = network.apply(params, obs)
    q_taken = jnp.take_along_axis(q_values, action[:, None], 1)[:, 0]
    loss = 0.5 * jnp.square(q_taken - jax.lax.stop_gradient(target)).mean()
    return loss, {"td_loss": loss, "q_mean": q_taken.mean()}


# --- the run ----------------------------------------------------------------------------------

def train(config: Config, out_dir, game=None, rom=None, progress: bool = True) -> dict:
    """Runs PQN for `config.num_seeds` seeds at once (`jax_training.train`); writes progress.csv,
    learning_curve.png and the params. Returns the summary (paths, speed, random and final returns)."""
    return jax_training.train(config, make_train, out_dir, game=game, rom=rom, progress=progress)


HELP = {
    "max_grad_norm": "global gradient-norm clip (PQN's 10; the paper gives none)",
    "q_lambda": "lambda of the Q(lambda) returns",
    "epsilon_start": "exploration rate of the first rollout",
    "epsilon_finish": "exploration rate after the decay",
    "epsilon_fraction": "fraction of total_steps over which epsilon decays linearly",
    "eval_epsilon": "exploration rate of the evaluated policy",
}


def parse_args(argv: Optional[Sequence[str]] = None) -> tuple[Config, Path]:
    return jax_training.parse_args(Config, HELP, __doc__.split("\n\n")[0], "runs/jax_pqn", argv)


def main(argv: Optional[Sequence[str]] = None) -> dict:
    config, out_dir = parse_args(argv)
    print(f"PQN on {config.game}: {config}")
    summary = train(config, out_dir)
    print(f"wrote {summary['csv']} and {summary['png']}")
    return summary


if __name__ == "__main__":
    main(sys.argv[1:])
