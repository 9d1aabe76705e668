"""PPO on an octax game, end to end in JAX: env steps, GAE and Adam updates in one jitted update.

    python examples/train_jax_ppo.py --game Airplane --num-envs 64 --num-minibatches 8 --total-steps 655360
    # 7-13 minutes on 2 CPU cores; the defaults (512 envs, 5M steps) are the paper's, for a GPU

The defaults are the paper's (Octax, Radji et al.; 512 envs, 32-step rollouts, 4 epochs of 32
minibatches, Adam 5e-4, GAE 0.95, clip 0.2, vf 0.5, entropy 0.01, gamma 0.99, grad norm 0.5) and its
network (a CNN for the (4, 64, 32) frames, separate 256-unit actor and critic heads). The learning
rate is constant (`--anneal-lr` decays it linearly to 0): the paper does not mention a schedule,
and its code (Rejax-based) passes a constant rate to Adam.

One update is `lax.scan` over `num_steps` vmapped env steps (same-step autoreset), GAE, then
`update_epochs` x `num_minibatches` Adam steps, all in one compiled call. Every `--eval-every`
env steps the current policy plays `--eval-envs` separate episodes to the end (actions sampled:
the policy is stochastic, as in the paper's evaluation), and a uniform-random policy is measured
the same way once at the start. Writes `progress.csv`, `learning_curve.png` and the final
`params.msgpack` (flax.serialization) to `--out-dir`. See docs/training.md.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import math
import sys
import time
from pathlib import Path
from typing import Any, Callable, NamedTuple, Optional, Sequence

import flax.linen as nn
import flax.serialization
import jax
import jax.numpy as jnp
import numpy as np
import optax
from tqdm import tqdm

import octax_core

CSV_COLUMNS = ("step", "update", "wall_s", "env_steps_per_s", "eval_mean_return", "eval_std",
               "eval_ended_frac", "random_mean_return", "train_episode_return", "train_episodes",
               "pg_loss", "v_loss", "entropy", "approx_kl", "clip_frac", "learning_rate")


@dataclasses.dataclass(frozen=True)
class Config:
    """Everything a run depends on; defaults are the paper's PPO settings."""

    game: str = "Brix"
    total_steps: int = 5_000_000  # env steps over all envs
    num_envs: int = 512
    num_steps: int = 32  # rollout length per env and update
    update_epochs: int = 4
    num_minibatches: int = 32
    learning_rate: float = 5e-4
    anneal_lr: bool = False  # off: the paper names none and its code uses a constant rate
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_eps: float = 0.2
    clip_value_loss: bool = True  # CleanRL's Atari PPO and the paper's Rejax-based code clip it
    vf_coef: float = 0.5
    ent_coef: float = 0.01
    max_grad_norm: float = 0.5
    seed: int = 0
    eval_every: int = 131_072  # env steps (the paper's); 0: only at the start and the end
    eval_envs: int = 128  # one episode each (the paper's 128 parallel envs)
    eval_max_steps: Optional[int] = None  # step cap per eval; None: the env's max_episode_steps
    env_overrides: tuple[tuple[str, Any], ...] = ()  # octax_core.make overrides, e.g. max_episode_steps

    @property
    def batch_size(self) -> int:
        return self.num_envs * self.num_steps

    @property
    def num_updates(self) -> int:
        return max(1, self.total_steps // self.batch_size)

    def check(self) -> None:
        """Raises ValueError when the batch does not split into minibatches."""
        if self.batch_size % self.num_minibatches:
            raise ValueError(f"num_envs * num_steps = {self.batch_size} is not divisible by "
                             f"num_minibatches = {self.num_minibatches}")


# --- network ----------------------------------------------------------------------------------

def _orthogonal(scale: float):
    return nn.initializers.orthogonal(scale)


def conv_valid(x: jax.Array, kernel: jax.Array, strides: tuple[int, int]) -> jax.Array:
    """A VALID, NHWC convolution as one matmul over strided slices (im2col), same values as
    `lax.conv_general_dilated`.

    Why not `nn.Conv`: on XLA's CPU backend the kernel gradient of a convolution inside a loop
    (our minibatch `lax.scan`) ran 50-130x slower than outside one (measured on this project's
    layers, jax 0.10), which made a PPO update 40x slower. Slices and a matmul differentiate into
    pads and matmuls, which run at full speed anywhere.
    """
    kh, kw, cin, cout = kernel.shape
    (sh, sw), (h, w) = strides, x.shape[1:3]
    oh, ow = (h - kh) // sh + 1, (w - kw) // sw + 1
    patches = [x[:, i:i + sh * (oh - 1) + 1:sh, j:j + sw * (ow - 1) + 1:sw]
               for i in range(kh) for j in range(kw)]
    return jnp.concatenate(patches, axis=-1) @ kernel.reshape(kh * kw * cin, cout)


class Conv(nn.Module):
    """`nn.Conv(features, kernel_size, strides, padding="VALID")`, computed by `conv_valid`."""

    features: int
    kernel_size: tuple[int, int]
    strides: tuple[int, int]

    @nn.compact
    def __call__(self, x: jax.Array) -> jax.Array:
        shape = (*self.kernel_size, x.shape[-1], self.features)
        kernel = self.param("kernel", _orthogonal(math.sqrt(2)), shape)
        bias = self.param("bias", nn.initializers.zeros, (self.features,))
        return conv_valid(x, kernel, self.strides) + bias


class ConvTorso(nn.Module):
    """The paper's feature extractor: (B, F, 32, 64) frames -> (B, 1024) for F = 4."""

    @nn.compact
    def __call__(self, obs: jax.Array) -> jax.Array:
        # (B, F, H=32, W=64) -> (B, 64, 32, F): the paper's (64, 32) image with the F frames as
        # channels (NHWC), so its (8, 4) kernel spans 8 columns and 4 rows.
        x = jnp.transpose(obs, (0, 3, 2, 1)).astype(jnp.float32)
        for features, kernel, strides in ((32, (8, 4), (4, 2)), (64, (4, 4), (2, 2)), (64, (3, 3), (1, 1))):
            x = nn.relu(Conv(features, kernel, strides)(x))  # 15x15x32 -> 6x6x64 -> 4x4x64
        return x.reshape(x.shape[0], -1)


class ActorCritic(nn.Module):
    """ConvTorso, then separate actor and critic heads of one 256-unit ReLU layer each."""

    num_actions: int

    @nn.compact
    def __call__(self, obs: jax.Array) -> tuple[jax.Array, jax.Array]:
        """Returns logits (B, num_actions) and values (B,)."""
        features = ConvTorso()(obs)
        # Orthogonal init as in CleanRL: small policy outputs start the policy near uniform.
        actor = nn.relu(nn.Dense(256, kernel_init=_orthogonal(math.sqrt(2)))(features))
        logits = nn.Dense(self.num_actions, kernel_init=_orthogonal(0.01))(actor)
        critic = nn.relu(nn.Dense(256, kernel_init=_orthogonal(math.sqrt(2)))(features))
        value = nn.Dense(1, kernel_init=_orthogonal(1.0))(critic)
        return logits, value[:, 0]


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


class Trainer(NamedTuple):
    """`init(key) -> RunnerState` and `update(runner) -> (runner, metrics)`, pure and jittable."""

    network: ActorCritic
    optimizer: optax.GradientTransformation
    init: Callable
    update: Callable


def make_optimizer(config: Config) -> optax.GradientTransformation:
    """Adam after global-norm clipping; the rate decays linearly to 0 with `anneal_lr`."""
    lr = config.learning_rate
    if config.anneal_lr:
        lr = optax.linear_schedule(lr, 0.0, config.num_updates * config.update_epochs * config.num_minibatches)
    return optax.chain(optax.clip_by_global_norm(config.max_grad_norm), optax.adam(lr))


def make_train(config: Config, env: octax_core.Env, env_params: octax_core.EnvParams) -> Trainer:
    """The PPO update for `env` (made with `autoreset=True`); jit `update` yourself."""
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
        final_value = jax.lax.cond(truncated.any(),
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

        def epoch(carry, _):
            params, opt_state, key = carry
            key, perm_key = jax.random.split(key)
            perm = jax.random.permutation(perm_key, config.batch_size)
            minibatches = jax.tree.map(
                lambda x: x[perm].reshape((config.num_minibatches, -1) + x.shape[1:]), batch)
            (params, opt_state), stats = jax.lax.scan(sgd_step, (params, opt_state), minibatches)
            return (params, opt_state, key), stats

        (params, opt_state, key), stats = jax.lax.scan(
            epoch, (runner.params, runner.opt_state, runner.key), None, config.update_epochs)
        metrics = {k: v.mean() for k, v in stats.items()}
        metrics["finished_return_sum"] = traj.finished_return.sum()
        metrics["finished_episodes"] = traj.done.sum()
        return runner._replace(params=params, opt_state=opt_state, key=key), metrics

    def sgd_step(carry, minibatch):
        params, opt_state = carry
        grads, stats = jax.grad(_ppo_loss, has_aux=True)(params, network, config, minibatch)
        updates, opt_state = optimizer.update(grads, opt_state, params)
        return (optax.apply_updates(params, updates), opt_state), stats

    return Trainer(network, optimizer, init, update)


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


# --- evaluation -------------------------------------------------------------------------------

def make_evaluate(env: octax_core.Env, env_params: octax_core.EnvParams, num_envs: int,
                  max_steps: int, act: Callable) -> Callable:
    """A jitted `evaluate(act_params, key) -> (returns, ended)`, both (num_envs,).

    Each of `num_envs` envs (made without autoreset) plays one episode with
    `act(act_params, key, obs) -> actions`, until every episode has ended or `max_steps` steps;
    `ended` is False for an episode the cap cut short (its return so far is kept).
    """
    if env.config.autoreset:
        raise ValueError("make_evaluate needs an env made with autoreset=False (one episode per env)")
    v_reset = jax.vmap(env.reset, in_axes=(0, None))
    v_step = jax.vmap(env.step, in_axes=(0, 0, 0, None))

    def evaluate(act_params, key):
        key, reset_key = jax.random.split(key)
        obs, state = v_reset(jax.random.split(reset_key, num_envs), env_params)
        zeros = jnp.zeros(num_envs, jnp.float32)
        carry = (jnp.int32(0), key, obs, state, zeros, jnp.zeros(num_envs, jnp.bool_))

        def running(carry):
            t, _, _, _, _, ended = carry
            return (t < max_steps) & ~ended.all()

        def body(carry):
            t, key, obs, state, returns, ended = carry
            key, act_key, step_key = jax.random.split(key, 3)
            action = act(act_params, act_key, obs)
            obs, state, reward, terminated, truncated, _ = v_step(
                jax.random.split(step_key, num_envs), state, action, env_params)
            # Ended episodes stand still and pay 0 (no autoreset), so summing is safe.
            return t + 1, key, obs, state, returns + reward, ended | terminated | truncated

        _, _, _, _, returns, ended = jax.lax.while_loop(running, body, carry)
        return returns, ended

    return jax.jit(evaluate)


def policy_act(network: ActorCritic) -> Callable:
    """Samples from the policy: the stochastic policy is what is evaluated."""
    return lambda params, key, obs: jax.random.categorical(key, network.apply(params, obs)[0])


def random_act(num_actions: int) -> Callable:
    return lambda _, key, obs: jax.random.randint(key, obs.shape[:1], 0, num_actions)


# --- the run ----------------------------------------------------------------------------------

def make_envs(config: Config, game=None, rom=None):
    """The training env (autoreset), the evaluation env (no autoreset) and their params."""
    game = config.game if game is None else game
    overrides = dict(config.env_overrides)
    env, env_params = octax_core.make(game, rom=rom, autoreset=True, **overrides)
    eval_env, _ = octax_core.make(game, rom=rom, autoreset=False, **overrides)
    return env, eval_env, env_params


def train(config: Config, out_dir, game=None, rom=None, progress: bool = True) -> dict:
    """Runs PPO, evaluating as configured; writes progress.csv, learning_curve.png, params.msgpack.

    `game` (an id or a `GameSpec`) and `rom` default to `config.game` and the ROM store.
    Returns a summary: paths, training speed (env steps/s, compile and evaluation excluded),
    the random baseline and the last evaluation.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    env, eval_env, env_params = make_envs(config, game, rom)
    trainer = make_train(config, env, env_params)
    eval_steps = config.eval_max_steps or int(env_params.max_episode_steps)
    evaluate_policy, evaluate_random = (
        make_evaluate(eval_env, env_params, config.eval_envs, eval_steps, act)
        for act in (policy_act(trainer.network), random_act(env.num_actions)))

    key, eval_key, random_key = jax.random.split(jax.random.key(config.seed), 3)
    runner = jax.jit(trainer.init)(key)
    compile_start = time.perf_counter()
    # Compiled ahead of time, so every timed call below runs and none compiles.
    update = jax.jit(trainer.update, donate_argnums=0).lower(runner).compile()
    print(f"compiled the PPO update in {time.perf_counter() - compile_start:.1f} s "
          f"({config.num_envs} envs x {config.num_steps} steps, {config.num_updates} updates)")
    random_returns, _ = evaluate_random(None, random_key)
    random_mean = float(np.mean(random_returns))
    print(f"random policy: mean return {random_mean:.2f} +- {np.std(random_returns):.2f} "
          f"over {config.eval_envs} episodes")

    title = f"PPO on {env.spec.id} ({config.num_envs} envs x {config.num_steps} steps)"
    log = _Log(out_dir, random_mean, title)
    start = time.perf_counter()
    bar = tqdm(total=config.num_updates * config.batch_size, unit="step", unit_scale=True,
               disable=not progress, desc=f"PPO {env.spec.id}")
    runner, train_s, row = _loop(config, update, runner, evaluate_policy, eval_key, log, bar, start)
    bar.close()
    (out_dir / "params.msgpack").write_bytes(flax.serialization.to_bytes(runner.params))
    steps_per_s = config.num_updates * config.batch_size / train_s
    print(f"training speed: {steps_per_s:,.0f} env steps/s (full loop: rollout + GAE + PPO epochs; "
          f"compile and evaluation excluded); wall {time.perf_counter() - start:.0f} s")
    print(f"final eval: {row['eval_mean_return']:.2f} +- {row['eval_std']:.2f} (random {random_mean:.2f})")
    return {"csv": log.csv_path, "png": log.png_path, "params": out_dir / "params.msgpack",
            "env_steps_per_s": steps_per_s, "random_mean_return": random_mean,
            "final_eval_mean_return": row["eval_mean_return"],
            "final_params": runner.params, "rows": log.rows}


def _loop(config: Config, update, runner, evaluate_policy, eval_key, log: "_Log", bar, start: float):
    """The updates, with an evaluation row every `eval_every` steps and at both ends.

    Returns the runner, the seconds spent in updates, and the last row.
    """
    eval_interval = config.num_updates
    if config.eval_every:
        eval_interval = max(1, round(config.eval_every / config.batch_size))
    train_s, totals = 0.0, {}
    for i in range(config.num_updates + 1):
        if i % eval_interval == 0 or i == config.num_updates:
            returns, ended = evaluate_policy(runner.params, jax.random.fold_in(eval_key, i))
            row = log.row(i, i * config.batch_size, time.perf_counter() - start, train_s, returns, ended,
                          totals, _learning_rate(config, i))
            bar.set_postfix(eval=f"{row['eval_mean_return']:.2f}", random=f"{log.random_mean:.2f}")
            totals = {}
        if i == config.num_updates:
            return runner, train_s, row
        t0 = time.perf_counter()
        runner, metrics = update(runner)
        metrics = jax.device_get(metrics)  # waits for the update: the timing covers all of it
        train_s += time.perf_counter() - t0
        for k, v in metrics.items():
            totals[k] = totals.get(k, 0.0) + float(v)
        totals["updates"] = totals.get("updates", 0) + 1
        bar.update(config.batch_size)


def _learning_rate(config: Config, update: int) -> float:
    if not config.anneal_lr:
        return config.learning_rate
    return config.learning_rate * max(0.0, 1.0 - update / config.num_updates)


class _Log:
    """Appends one CSV row per evaluation and redraws the learning curve."""

    def __init__(self, out_dir: Path, random_mean: float, title: str):
        self.csv_path, self.png_path = out_dir / "progress.csv", out_dir / "learning_curve.png"
        self.random_mean, self.title, self.rows = random_mean, title, []
        with open(self.csv_path, "w", newline="") as f:
            csv.writer(f).writerow(CSV_COLUMNS)

    def row(self, update, step, wall_s, train_s, returns, ended, totals, lr) -> dict:
        returns, ended = np.asarray(returns), np.asarray(ended)
        n = totals.get("updates", 0)
        episodes = totals.get("finished_episodes", 0.0)
        mean = lambda k: totals[k] / n if n else math.nan
        row = {"step": step, "update": update, "wall_s": round(wall_s, 2),
               "env_steps_per_s": round(step / train_s, 1) if train_s else math.nan,
               "eval_mean_return": float(returns.mean()), "eval_std": float(returns.std()),
               "eval_ended_frac": float(ended.mean()), "random_mean_return": self.random_mean,
               "train_episode_return": totals["finished_return_sum"] / episodes if episodes else math.nan,
               "train_episodes": int(episodes), **{k: mean(k) for k in ("pg_loss", "v_loss", "entropy",
                                                                       "approx_kl", "clip_frac")},
               "learning_rate": lr}
        self.rows.append(row)
        with open(self.csv_path, "a", newline="") as f:
            csv.DictWriter(f, CSV_COLUMNS).writerow(row)
        self._plot()
        return row

    def _plot(self) -> None:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        step = np.array([r["step"] for r in self.rows])
        mean = np.array([r["eval_mean_return"] for r in self.rows])
        std = np.array([r["eval_std"] for r in self.rows])
        train_return = np.array([r["train_episode_return"] for r in self.rows], float)
        fig, ax = plt.subplots(figsize=(7, 4))
        ax.plot(step, mean, "o-", label="eval (stochastic policy), mean")
        ax.fill_between(step, mean - std, mean + std, alpha=0.2, label="eval, +- 1 std")
        ax.plot(step, train_return, ".--", alpha=0.7, label="training episodes, mean")
        ax.axhline(self.random_mean, color="gray", linestyle=":", label="random policy")
        ax.set_xlabel("env steps")
        ax.set_ylabel("episode return")
        ax.set_title(self.title)
        ax.legend(loc="best", fontsize="small")
        fig.tight_layout()
        fig.savefig(self.png_path, dpi=100)
        plt.close(fig)


# --- command line -----------------------------------------------------------------------------

HELP = {
    "game": "a registered octax game id (python -m octax_gym list)",
    "total_steps": "env steps over all envs (rounded down to whole updates)",
    "num_envs": "parallel training envs",
    "num_steps": "rollout length per env and update",
    "update_epochs": "passes over each rollout",
    "num_minibatches": "Adam steps per epoch (num_envs * num_steps must divide)",
    "learning_rate": "Adam step size",
    "anneal_lr": "decay the learning rate linearly to 0 (the paper: constant)",
    "gamma": "discount",
    "gae_lambda": "GAE lambda",
    "clip_eps": "PPO ratio clip (and value clip)",
    "clip_value_loss": "clip the value loss as CleanRL's Atari PPO does",
    "vf_coef": "value loss weight",
    "ent_coef": "entropy bonus weight",
    "max_grad_norm": "global gradient-norm clip",
    "seed": "seeds the network, the envs and the evaluations",
    "eval_every": "env steps between evaluations; 0: only at the start and the end",
    "eval_envs": "evaluation episodes (one per env), played to their end",
    "eval_max_steps": "step cap per evaluation; None: the env's max_episode_steps",
}
ENV_FLAGS = {"max_episode_steps": int, "frames_per_step": int, "repeat_action_probability": float,
             "noop_max": int}


def parse_args(argv: Optional[Sequence[str]] = None) -> tuple[Config, Path]:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    for field in dataclasses.fields(Config):
        if field.name == "env_overrides":
            continue
        flag = "--" + field.name.replace("_", "-")
        help_text = HELP[field.name]
        if field.type in ("bool", bool):
            parser.add_argument(flag, action=argparse.BooleanOptionalAction, default=field.default,
                                help=help_text)
        elif field.name == "eval_max_steps":
            parser.add_argument(flag, type=int, default=None, help=help_text)
        else:
            parser.add_argument(flag, type=type(field.default), default=field.default, help=help_text)
    for name, kind in ENV_FLAGS.items():
        parser.add_argument("--" + name.replace("_", "-"), type=kind, default=None,
                            help="octax_core.make override; None: the game's")
    parser.add_argument("--out-dir", type=Path, default=None,
                        help="for progress.csv, learning_curve.png and params.msgpack; "
                             "None: runs/jax_ppo/<game>-s<seed>")
    args = vars(parser.parse_args(argv))
    out_dir = args.pop("out_dir")
    overrides = tuple((k, args.pop(k)) for k in ENV_FLAGS if args[k] is not None)
    for k in ENV_FLAGS:
        args.pop(k, None)
    config = Config(**args, env_overrides=overrides)
    config.check()
    return config, out_dir or Path("runs/jax_ppo") / f"{config.game}-s{config.seed}"


def main(argv: Optional[Sequence[str]] = None) -> dict:
    config, out_dir = parse_args(argv)
    print(f"PPO on {config.game}: {config}")
    summary = train(config, out_dir)
    print(f"wrote {summary['csv']} and {summary['png']}")
    return summary


if __name__ == "__main__":
    main(sys.argv[1:])
