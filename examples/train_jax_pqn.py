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
`--num-seeds S` included, and the same rollout and minibatch epochs (examples/jax_update.py); this
file holds what is PQN's: epsilon-greedy acting, the Q(lambda) targets and the TD loss. See
docs/training.md.
"""

from __future__ import annotations

import dataclasses
import sys
from typing import Any, Optional, Sequence

import jax
import jax.numpy as jnp

import octax_core
import jax_training
import jax_update
from jax_networks import QNetwork
from jax_training import RunConfig, Trainer, make_envs, make_evaluate, random_act  # noqa: F401

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


def epsilon_greedy(q_values: jax.Array, key: jax.Array, epsilon) -> jax.Array:
    """argmax Q, or with probability epsilon a uniformly random action, per row."""
    explore_key, action_key = jax.random.split(key)
    random_action = jax.random.randint(action_key, q_values.shape[:1], 0, q_values.shape[1])
    explore = jax.random.uniform(explore_key, q_values.shape[:1]) < epsilon
    return jnp.where(explore, random_action, jnp.argmax(q_values, axis=1))


def make_train(config: Config, env: octax_core.Env, env_params: octax_core.EnvParams) -> Trainer:
    """PQN for `env` (made with `autoreset=True`): a `Trainer` of one agent; jit `update` yourself
    (`jax_training.train` maps it over seeds and compiles it)."""
    config.check()
    network, optimizer = QNetwork(env.num_actions), jax_update.make_optimizer(config)

    def explore(params, key, obs, epsilon):
        q_values = network.apply(params, obs)
        return epsilon_greedy(q_values, key, epsilon), q_values.max(axis=1)

    def max_q(params, obs):
        return network.apply(params, obs).max(axis=1)

    rollout = jax_update.make_rollout(config, env, env_params, explore, max_q)
    learn = jax_update.make_learn(config, optimizer, lambda params, minibatch: _td_loss(params, network, minibatch))

    def update(runner: jax_update.RunnerState):
        epsilon = config.epsilon(runner.updates)
        runner, traj = rollout(runner, epsilon)
        targets = q_lambda_targets(traj.reward, traj.done, traj.policy_out, max_q(runner.params, runner.obs),
                                   config.gamma, config.q_lambda)
        runner, metrics = learn(runner, (traj.obs, traj.action, targets))
        metrics.update(target_mean=targets.mean(), epsilon=epsilon, **jax_update.episode_totals(traj))
        return runner, metrics

    def act(params, key, obs):
        return epsilon_greedy(network.apply(params, obs), key, config.eval_epsilon)

    return Trainer("PQN", network, jax_update.make_init(config, env, env_params, network, optimizer), update, act,
                   lambda runner: runner.params, METRICS,
                   lambda i: {"learning_rate": config.learning_rate_at(i), "epsilon": float(config.epsilon(i))})


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


def main(argv: Optional[Sequence[str]] = None) -> dict:
    """The command line (`jax_training.main`): flags, training, and the summary returned."""
    return jax_training.main("PQN", Config, make_train, HELP, __doc__, "runs/jax_pqn", argv)


if __name__ == "__main__":
    main(sys.argv[1:])
