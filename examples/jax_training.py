"""What the pure-JAX PPO and PQN examples share around their updates: settings, envs, evaluation,
many seeds in one program, the log (CSV and learning curve), the training loop and the command
line (`main`). What their updates share (the runner, the rollout, the minibatch epochs) is
examples/jax_update.py.

An algorithm is a `Trainer`: `init(key) -> runner` and `update(runner) -> (runner, metrics)`, pure
functions of one agent. `train` runs `config.num_seeds` agents at once: seed i starts from
`jax.random.key(config.seed + i)` and every function is mapped over seeds with `jax.vmap`, so S
agents are one compiled program (their env steps and matrix products batched together) and agent i
learns what a run with `--seed` `config.seed + i` alone learns (tests/examples check it). With one
seed the functions run as they are, unmapped.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import math
import sys
import time
from pathlib import Path
from typing import Any, Callable, NamedTuple, Optional, Sequence

import flax.serialization
import jax
import jax.numpy as jnp
import numpy as np
from tqdm import tqdm

import octax_core
from octax_gym.scores import iqm

LOOP_FIELDS = ("save_at_evals", "checkpoint_every", "devices")  # what `train`'s loop does, flags of `main` only
COMMON_COLUMNS = ("seed", "step", "update", "wall_s", "env_steps_per_s", "eval_mean_return", "eval_std",
                  "eval_ended_frac", "random_mean_return", "train_episode_return", "train_episodes")


@dataclasses.dataclass(frozen=True)
class RunConfig:
    """The settings every algorithm has; defaults are the paper's (512 envs x 32 steps, 4 epochs of
    32 minibatches, Adam 5e-4, evaluation every 131,072 steps on 128 envs)."""

    game: str = "Brix"
    total_steps: int = 5_000_000  # env steps over all envs, per seed
    num_envs: int = 512
    num_steps: int = 32  # rollout length per env and update
    update_epochs: int = 4
    num_minibatches: int = 32
    learning_rate: float = 5e-4
    anneal_lr: bool = False  # off: the paper names no schedule and its code uses a constant rate
    gamma: float = 0.99
    max_grad_norm: float = 0.5
    seed: int = 0
    num_seeds: int = 1  # agents trained at once, seeds seed .. seed + num_seeds - 1
    eval_every: int = 131_072  # env steps (the paper's); 0: only at the start and the end
    eval_envs: int = 128  # one episode each (the paper's 128 parallel envs)
    eval_max_steps: Optional[int] = None  # step cap per eval; None: the env's max_episode_steps
    save_at_evals: bool = False  # also write the params at every evaluation (checkpoints/params-step<N>...)
    checkpoint_every: int = 0  # updates between resumable checkpoints (resume/checkpoint.msgpack); 0: none
    devices: str = ""  # "": one device; "all": every seed's envs split over every device of every process
    env_overrides: tuple[tuple[str, Any], ...] = ()  # octax_core.make overrides, e.g. max_episode_steps

    @property
    def batch_size(self) -> int:
        return self.num_envs * self.num_steps

    @property
    def num_updates(self) -> int:
        return max(1, self.total_steps // self.batch_size)

    @property
    def seeds(self) -> list[int]:
        return [self.seed + i for i in range(self.num_seeds)]

    def learning_rate_at(self, update: int) -> float:
        """Adam's rate during update number `update` (from 0): constant, or with `anneal_lr`
        decaying linearly to 0 over the run, as `jax_update.make_optimizer`'s schedule does."""
        if not self.anneal_lr:
            return self.learning_rate
        return self.learning_rate * max(0.0, 1.0 - update / self.num_updates)

    def check(self) -> None:
        """Raises ValueError for settings no run can use, naming the setting."""
        if self.batch_size % self.num_minibatches:
            raise ValueError(f"num_envs * num_steps = {self.batch_size} is not divisible by "
                             f"num_minibatches = {self.num_minibatches}")
        if self.num_seeds < 1:
            raise ValueError(f"num_seeds must be at least 1, got {self.num_seeds}")
        if self.devices not in ("", "all"):
            raise ValueError(f"devices must be '' (one device) or 'all' (data-parallel over every device), "
                             f"got {self.devices!r}")
        if self.checkpoint_every < 0:
            raise ValueError(f"checkpoint_every must be >= 0 (0: no checkpoints), got {self.checkpoint_every}")


class Trainer(NamedTuple):
    """One algorithm for one env: pure functions of one agent, jittable and vmappable."""

    name: str  # "PPO", "PQN": titles and the progress bar
    network: Any  # the flax module
    init: Callable  # key -> runner
    update: Callable  # runner -> (runner, metrics): one rollout and its epochs
    act: Callable  # (params, key, obs) -> actions: the policy that is evaluated
    params: Callable  # runner -> the network's params
    metric_names: tuple[str, ...]  # per-update metrics, averaged between evaluations in the CSV
    host_metrics: Callable  # update index -> {name: value} for schedules (learning rate, epsilon)


# --- envs and evaluation ----------------------------------------------------------------------

def make_envs(config: RunConfig, game=None, rom=None):
    """The training env (autoreset), the evaluation env (no autoreset) and their params."""
    game = config.game if game is None else game
    overrides = dict(config.env_overrides)
    env, env_params = octax_core.make(game, rom=rom, autoreset=True, **overrides)
    eval_env, _ = octax_core.make(game, rom=rom, autoreset=False, **overrides)
    return env, eval_env, env_params


def make_evaluate(env: octax_core.Env, env_params: octax_core.EnvParams, num_envs: int,
                  max_steps: int, act: Callable, jit: bool = True) -> Callable:
    """`evaluate(act_params, key) -> (returns, ended)`, both (num_envs,), jitted unless `jit=False`.

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

    return jax.jit(evaluate, compiler_options=env.compiler_options) if jit else evaluate


def random_act(num_actions: int) -> Callable:
    return lambda _, key, obs: jax.random.randint(key, obs.shape[:1], 0, num_actions)


# --- many seeds in one program -----------------------------------------------------------------

SEED_AXIS = "seeds"  # the vmap axis name of the seeds, for `any_over_seeds`


def any_over_seeds(flags: jax.Array, num_seeds: int) -> jax.Array:
    """Whether any of `flags` is set, in this agent's envs or, with several seeds, in any seed's.

    For a `lax.cond` that should stay a branch under the seed map: with a per-seed predicate
    `vmap` turns a cond into a select that runs both branches every time (the truncation
    bootstrap's network pass on every step: 9% of a seed's time, measured), while a predicate
    shared by all seeds (a `psum` over the seed axis) keeps it a cond, taken when any seed needs it.
    Call it inside functions mapped by `over_seeds` with the same `num_seeds`.
    """
    count = flags.any().astype(jnp.int32)
    if num_seeds > 1:
        count = jax.lax.psum(count, SEED_AXIS)
    return count > 0


def over_seeds(fn: Callable, num_seeds: int, in_axes=0) -> Callable:
    """`fn` mapped over a leading seed axis: `jax.vmap` for several seeds; for one, `fn` itself on
    the lone seed's slice (the result gets its seed axis back), so a one-seed run is the plain program."""
    if num_seeds > 1:
        return jax.vmap(fn, in_axes=in_axes, axis_name=SEED_AXIS)
    axes = in_axes if isinstance(in_axes, tuple) else None

    def lone(*args):
        sliced = [a if axes is not None and axes[i] is None else jax.tree.map(lambda x: x[0], a)
                  for i, a in enumerate(args)]
        return jax.tree.map(lambda x: x[None], fn(*sliced))

    return lone


def init_seeds(init: Callable, keys: jax.Array):
    """`init` run for each seed's key, the results stacked along a leading seed axis.

    One call per seed rather than `jax.vmap(init)`: mapped over keys, initialising either
    example's network never returned on XLA's CPU backend here (jax 0.10.2; each initializer and
    layer mapped alone ran, the whole did not, the same call unmapped takes milliseconds; cause
    not found). Initialising is done once, so nothing is lost, and each seed gets exactly what a
    run of that seed alone gets.
    """
    init = jax.jit(init)
    return jax.tree.map(lambda *leaves: jnp.stack(leaves), *[init(key) for key in keys])


def seed_keys(config: RunConfig) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Per seed (each (num_seeds,)): the training key, the evaluation key and the random baseline's
    key, all from `jax.random.key(seed)` as a run of that seed alone makes them."""
    keys = jnp.stack([jax.random.split(jax.random.key(s), 3) for s in config.seeds])
    return keys[:, 0], keys[:, 1], keys[:, 2]


# --- the run ----------------------------------------------------------------------------------

def train(config: RunConfig, make_train: Callable, out_dir, game=None, rom=None, progress: bool = True,
          resume: bool = False) -> dict:
    """Trains `config.num_seeds` agents of `make_train(config, env, env_params) -> Trainer` at once,
    evaluating as configured; writes config.json (the algorithm, the env and every setting),
    progress.csv, learning_curve.png and the params to `out_dir`.

    `game` (an id or a `GameSpec`) and `rom` default to `config.game` and the ROM store. Returns a
    summary: paths, training speed (env steps/s over all seeds, compile and evaluation excluded),
    the random baseline and the last evaluation (means over seeds, and per seed).

    `resume`: continue the run in `out_dir` from its last checkpoint (`config.checkpoint_every`):
    the runner, the update count, the metric sums since the last evaluation and the log's rows up
    to that update come back, and the rest of the run is the one an uninterrupted run does.
    """
    config.check()
    out_dir = Path(out_dir)
    writer = jax.process_index() == 0  # in a multi-process run, process 0 alone writes files
    out_dir.mkdir(parents=True, exist_ok=True)
    checkpoints = Checkpoints(out_dir / "resume", write=writer)
    parallel = DataParallel(config) if config.devices else None
    env, eval_env, env_params = make_envs(config, game, rom)
    trainer = make_train(config, env, env_params)
    seeds = config.num_seeds
    eval_steps = config.eval_max_steps or int(env_params.max_episode_steps)
    # Every jit that steps the env takes its platform's compiler options (exact; faster kernels).
    options = env.compiler_options
    evaluate_policy = jax.jit(over_seeds(
        make_evaluate(eval_env, env_params, config.eval_envs, eval_steps, trainer.act, jit=False), seeds),
        compiler_options=options)
    evaluate_random = jax.jit(over_seeds(
        make_evaluate(eval_env, env_params, config.eval_envs, eval_steps, random_act(env.num_actions), jit=False),
        seeds, in_axes=(None, 0)), compiler_options=options)

    if not resume and writer:
        (out_dir / "config.json").write_text(json.dumps(
            {"algorithm": trainer.name, "env_id": env.spec.id, "command": sys.argv,
             **dataclasses.asdict(config)}, indent=2, default=str) + "\n")
    train_keys, eval_keys, random_keys = seed_keys(config)
    runner = init_seeds(trainer.init, train_keys)
    start_at = None
    if resume:
        runner, start_at = checkpoints.load(runner)
        print(f"resuming {out_dir} at update {start_at['update']} of {config.num_updates}")
    shardings = {}
    if parallel is not None:
        runner = parallel.place(runner)
        eval_keys, random_keys = parallel.replicate(eval_keys), parallel.replicate(random_keys)
        shardings = {"in_shardings": (parallel.shardings(runner),),
                     "out_shardings": (parallel.shardings(runner), parallel.replicated)}
    compile_start = time.perf_counter()
    # Compiled ahead of time, so every timed call below runs and none compiles.
    update = jax.jit(over_seeds(trainer.update, seeds), donate_argnums=0, compiler_options=options,
                     **shardings).lower(runner).compile()
    print(f"compiled the {trainer.name} update in {time.perf_counter() - compile_start:.1f} s "
          f"({seeds} seed{'s' * (seeds > 1)} x {config.num_envs} envs x {config.num_steps} steps, "
          f"{config.num_updates} updates)")
    random_returns, _ = jax.device_get(evaluate_random(None, random_keys))
    random_means = random_returns.mean(axis=1)
    print(f"random policy: mean return {random_returns.mean():.2f} +- {random_returns.std():.2f} "
          f"over {config.eval_envs} episodes x {seeds} seed(s)")

    title = f"{trainer.name} on {env.spec.id} ({config.num_envs} envs x {config.num_steps} steps" + (
        f", {seeds} seeds)" if seeds > 1 else ")")
    log = RunLog(out_dir, config.seeds, random_means, title, trainer.metric_names,
                 keep_until=None if start_at is None else start_at["update"], write=writer)
    start = time.perf_counter()
    bar = tqdm(total=config.num_updates * config.batch_size * seeds, unit="step", unit_scale=True,
               disable=not progress or not writer, desc=f"{trainer.name} {env.spec.id}" + (f" x{seeds}" if seeds > 1 else ""))

    def save_params(params, folder: Path, stem: str) -> list[Path]:
        params = host_values(params)  # every process takes part; process 0 writes
        paths = []
        for i, seed in enumerate(config.seeds):
            path = folder / (f"{stem}.msgpack" if seeds == 1 else f"{stem}-seed{seed}.msgpack")
            if writer:
                path.write_bytes(flax.serialization.to_bytes(jax.tree.map(lambda x: x[i], params)))
            paths.append(path)
        return paths

    checkpoint = None
    if config.save_at_evals:
        (out_dir / "checkpoints").mkdir(exist_ok=True)
        checkpoint = lambda step, params: save_params(params, out_dir / "checkpoints", f"params-step{step}")  # noqa: E731
    if start_at is not None:
        bar.update(start_at["update"] * config.batch_size * seeds)
    save = checkpoints.save if config.checkpoint_every else None
    runner, train_s, rows = _loop(config, trainer, update, runner, evaluate_policy, eval_keys, log, bar, start,
                                  checkpoint, save, start_at)
    bar.close()
    params = trainer.params(runner)
    param_paths = save_params(params, out_dir, "params")
    steps_per_s = config.num_updates * config.batch_size * seeds / train_s
    final = np.array([row["eval_mean_return"] for row in rows])
    print(f"training speed: {steps_per_s:,.0f} env steps/s over {seeds} seed(s), "
          f"{train_s / seeds:.1f} s of training per seed (full loop: rollout, targets and epochs; "
          f"compile and evaluation excluded); wall {time.perf_counter() - start:.0f} s")
    print(f"final eval: {final.mean():.2f} (per seed: {', '.join(f'{r:.2f}' for r in final)}); "
          f"random {random_means.mean():.2f}")
    return {"csv": log.csv_path, "png": log.png_path, "params": param_paths[0], "param_paths": param_paths,
            "env_steps_per_s": steps_per_s, "train_s": train_s, "train_s_per_seed": train_s / seeds,
            "random_mean_return": float(random_means.mean()), "final_eval_mean_return": float(final.mean()),
            "random_mean_returns": random_means.tolist(), "final_eval_mean_returns": final.tolist(),
            "final_params": host_values(params) if seeds > 1 else jax.tree.map(lambda x: x[0], host_values(params)),
            "rows": log.rows}


def _loop(config: RunConfig, trainer: Trainer, update, runner, evaluate_policy, eval_keys, log: "RunLog",
          bar, start: float, checkpoint: Optional[Callable] = None, save: Optional[Callable] = None,
          start_at: Optional[dict] = None):
    """The updates, with an evaluation of every seed every `eval_every` steps and at both ends
    (and `checkpoint(step, params)` after each, when given). With `save`, every
    `checkpoint_every` updates `save(runner, position)` writes a resumable checkpoint; `start_at`
    (a loaded one's position) starts the loop where it was written.

    Returns the runner, the seconds spent in updates, and the last evaluation's rows (one per seed).
    """
    eval_interval = config.num_updates
    if config.eval_every:
        eval_interval = max(1, round(config.eval_every / config.batch_size))
    fold = jax.jit(jax.vmap(jax.random.fold_in, in_axes=(0, None)))
    train_s, totals, first, rows = 0.0, {}, 0, log.rows[-len(config.seeds):]
    if start_at is not None:
        first, train_s, totals = start_at["update"], start_at["train_s"], start_at["totals"]
    for i in range(first, config.num_updates + 1):
        resumed_here = start_at is not None and i == first  # its evaluation and checkpoint are on disk
        if (i % eval_interval == 0 or i == config.num_updates) and not resumed_here:
            returns, ended = jax.device_get(evaluate_policy(trainer.params(runner), fold(eval_keys, i)))
            rows = log.add(i, i * config.batch_size, time.perf_counter() - start, train_s, returns, ended,
                           totals, trainer.host_metrics(i))
            bar.set_postfix(eval=f"{np.mean(returns):.2f}", random=f"{np.mean(log.random_means):.2f}")
            if checkpoint is not None:
                checkpoint(i * config.batch_size, trainer.params(runner))
            totals = {}
        if i == config.num_updates:
            return runner, train_s, rows
        if save is not None and i % config.checkpoint_every == 0 and i > 0 and not resumed_here:
            save(runner, {"update": i, "train_s": train_s, "totals": totals})
        t0 = time.perf_counter()
        runner, metrics = update(runner)
        metrics = jax.device_get(metrics)  # waits for the update: the timing covers all of it
        train_s += time.perf_counter() - t0
        for k, v in metrics.items():
            totals[k] = totals.get(k, 0.0) + np.asarray(v, np.float64)
        totals["updates"] = totals.get("updates", 0) + 1
        bar.update(config.batch_size * config.num_seeds)


class DataParallel:
    """Data-parallel placement of a run (`devices="all"`): a 1-D mesh "envs" over every device of
    every process; each seed's envs (the runner's env states, observations and running returns,
    axis 1 after the seed axis) split along it, everything else (params, optimizer state, keys)
    replicated. The update is compiled with these shardings, so XLA runs each device's envs where
    they live and averages the loss, hence the gradients, over the whole batch with its own
    collectives: the algorithm's code is unchanged, and the params are those of one device up to
    the order of float sums."""

    BATCH_FIELDS = ("env_state", "obs", "episode_return")

    def __init__(self, config: RunConfig):
        from jax.sharding import Mesh, NamedSharding, PartitionSpec

        self.mesh = Mesh(np.array(jax.devices()), ("envs",))
        if config.num_envs % self.mesh.size:
            raise ValueError(f"num_envs={config.num_envs} does not divide over the {self.mesh.size} devices "
                             f"(devices='all'); use a multiple of {self.mesh.size}")
        self.batch = NamedSharding(self.mesh, PartitionSpec(None, "envs"))
        self.replicated = NamedSharding(self.mesh, PartitionSpec())

    def shardings(self, runner):
        fields = {name: jax.tree.map(lambda _: self.batch if name in self.BATCH_FIELDS else self.replicated,
                                     getattr(runner, name)) for name in runner._fields}
        return type(runner)(**fields)

    def place(self, runner):
        """The runner (the same values on every process) as global arrays with `shardings`."""
        shardings = self.shardings(runner)
        host = host_values(_keys_as_data(runner))
        placed = jax.tree.map(lambda x, s: jax.make_array_from_callback(np.shape(x), s, lambda i: np.asarray(x)[i]),
                              host, shardings)
        return jax.tree.map(lambda t, x: jax.random.wrap_key_data(x, impl=jax.random.key_impl(t)) if _is_key(t) else x,
                            runner, placed)

    def replicate(self, keys):
        data = np.asarray(jax.random.key_data(keys))
        placed = jax.make_array_from_callback(data.shape, self.replicated, lambda i: data[i])
        return jax.random.wrap_key_data(placed, impl=jax.random.key_impl(keys))


def host_values(tree):
    """Every leaf as a numpy array on every process: a multi-process array that is not fully
    replicated is gathered (`process_allgather`, a collective: every process must call this)."""
    from jax.experimental import multihost_utils

    def leaf(x):
        if isinstance(x, jax.Array) and not x.is_fully_addressable and not x.is_fully_replicated:
            return np.asarray(multihost_utils.process_allgather(x, tiled=True))
        return np.asarray(x)
    return jax.tree.map(leaf, tree)


class Checkpoints:
    """A run's resumable checkpoint: `<out_dir>/resume/checkpoint.msgpack` (flax serialization of
    every seed's runner, typed PRNG keys as their raw data, and the loop's position: updates done,
    training seconds, the metric sums since the last evaluation) and `checkpoint.json` (the
    position, readable). Each is written to a temporary file and renamed over the last one, so a
    kill at any moment leaves the previous checkpoint or the new one whole, never a torn file."""

    def __init__(self, folder: Path, write: bool = True):
        self.folder, self.write = folder, write
        self.path, self.info_path = folder / "checkpoint.msgpack", folder / "checkpoint.json"

    def save(self, runner, position: dict) -> None:
        leaves = jax.tree.leaves(host_values(_keys_as_data(runner)))  # every process takes part
        if not self.write:
            return
        self.folder.mkdir(parents=True, exist_ok=True)
        payload = {"runner": {str(i): np.asarray(leaf) for i, leaf in enumerate(leaves)},
                   "update": position["update"], "train_s": position["train_s"],
                   "totals": {k: np.asarray(v, np.float64) for k, v in position["totals"].items()}}
        _replace(self.path, flax.serialization.msgpack_serialize(payload))
        _replace(self.info_path, (json.dumps({"update": position["update"]}) + "\n").encode())

    def load(self, template):
        """The runner (shaped as `template`, a freshly initialised one) and the position."""
        if not self.path.is_file():
            raise FileNotFoundError(f"no checkpoint to resume from at {self.path} (was the run started with "
                                    "--checkpoint-every N, and had it written one?)")
        state = flax.serialization.msgpack_restore(self.path.read_bytes())
        expected, treedef = jax.tree.flatten(_keys_as_data(template))
        leaves = [state["runner"][str(i)] for i in range(len(state["runner"]))]
        if [(np.shape(a), np.asarray(a).dtype) for a in leaves] != [(a.shape, a.dtype) for a in expected]:
            raise ValueError(f"{self.path} holds a runner of another shape (another config or algorithm)")
        runner = jax.tree.map(lambda t, x: jax.random.wrap_key_data(x, impl=jax.random.key_impl(t))
                              if _is_key(t) else jnp.asarray(x), template, treedef.unflatten(leaves))
        totals = {k: (int(v) if k == "updates" else np.asarray(v, np.float64)) for k, v in state["totals"].items()}
        return runner, {"update": int(state["update"]), "train_s": float(state["train_s"]), "totals": totals}


def _is_key(x) -> bool:
    return isinstance(x, jax.Array) and jnp.issubdtype(x.dtype, jax.dtypes.prng_key)


def _keys_as_data(tree):
    return jax.tree.map(lambda x: jax.random.key_data(x) if _is_key(x) else x, tree)


def _replace(path: Path, data: bytes) -> None:
    temporary = path.with_suffix(path.suffix + ".tmp")
    temporary.write_bytes(data)
    temporary.replace(path)


def _number(text: str):
    """A CSV cell back as the int or float it was written from."""
    try:
        return int(text)
    except ValueError:
        return float(text)


class RunLog:
    """Appends one CSV row per seed and evaluation, and redraws the learning curve."""

    def __init__(self, out_dir: Path, seeds: Sequence[int], random_means, title: str, metric_names: Sequence[str],
                 keep_until: Optional[int] = None, write: bool = True):
        """A new log; or, with `keep_until` (a resumed run's update), the existing progress.csv's rows
        up to that update, rewritten without the rows a killed run logged after its checkpoint."""
        self.csv_path, self.png_path = out_dir / "progress.csv", out_dir / "learning_curve.png"
        self.seeds, self.random_means = list(seeds), np.asarray(random_means, np.float64)
        self.title, self.metric_names, self.rows = title, tuple(metric_names), []
        self.columns = COMMON_COLUMNS + self.metric_names
        self._extra_columns: Optional[tuple[str, ...]] = None
        self.write = write
        if not write:
            return
        if keep_until is not None:
            with open(self.csv_path, newline="") as f:
                self.rows = [{k: _number(v) for k, v in row.items()} for row in csv.DictReader(f)
                             if int(row["update"]) <= keep_until]
        with open(self.csv_path, "w", newline="") as f:
            csv.writer(f).writerow(self.columns)
            csv.DictWriter(f, self.columns).writerows(self.rows)

    def add(self, update, step, wall_s, train_s, returns, ended, totals, host_metrics) -> list[dict]:
        """Rows for one evaluation: `returns` and `ended` are (num_seeds, eval_envs); `totals` holds
        each metric's (num_seeds,) sum over the updates since the last evaluation."""
        returns, ended = np.asarray(returns), np.asarray(ended)
        n = totals.get("updates", 0)
        rows = []
        for i, seed in enumerate(self.seeds):
            episodes = float(totals["finished_episodes"][i]) if n else 0.0
            row = {"seed": seed, "step": step, "update": update, "wall_s": round(wall_s, 2),
                   "env_steps_per_s": round(step * len(self.seeds) / train_s, 1) if train_s else math.nan,
                   "eval_mean_return": float(returns[i].mean()), "eval_std": float(returns[i].std()),
                   "eval_ended_frac": float(ended[i].mean()), "random_mean_return": float(self.random_means[i]),
                   "train_episode_return": (float(totals["finished_return_sum"][i]) / episodes
                                            if episodes else math.nan),
                   "train_episodes": int(episodes)}
            for name in self.metric_names:
                row[name] = float(totals[name][i]) / n if n and name in totals else host_metrics.get(name, math.nan)
            rows.append(row)
        self.rows.extend(rows)
        if self.write:
            with open(self.csv_path, "a", newline="") as f:
                csv.DictWriter(f, self.columns).writerows(rows)
            self._plot()
        return rows

    def _plot(self) -> None:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 4))
        by_seed = {seed: [r for r in self.rows if r["seed"] == seed] for seed in self.seeds}
        step = np.array([r["step"] for r in by_seed[self.seeds[0]]])
        mean = np.array([[r["eval_mean_return"] for r in rows] for rows in by_seed.values()])  # (seeds, evals)
        if len(self.seeds) == 1:
            std = np.array([r["eval_std"] for r in by_seed[self.seeds[0]]])
            ax.plot(step, mean[0], "o-", label="eval, mean")
            ax.fill_between(step, mean[0] - std, mean[0] + std, alpha=0.2, label="eval, +- 1 std")
            train_return = np.array([r["train_episode_return"] for r in by_seed[self.seeds[0]]], float)
            ax.plot(step, train_return, ".--", alpha=0.7, label="training episodes, mean")
        else:
            for seed, curve in zip(self.seeds, mean):
                ax.plot(step, curve, "-", alpha=0.35, linewidth=1)
            ax.plot(step, [iqm(column) for column in mean.T], "o-", color="C0",
                    label=f"eval, IQM of {len(self.seeds)} seeds (thin: each seed)")
        ax.axhline(self.random_means.mean(), color="gray", linestyle=":", label="random policy")
        ax.set_xlabel("env steps (per seed)")
        ax.set_ylabel("episode return")
        ax.set_title(self.title)
        ax.legend(loc="best", fontsize="small")
        fig.tight_layout()
        fig.savefig(self.png_path, dpi=100)
        plt.close(fig)


# --- command line -----------------------------------------------------------------------------

HELP = {
    "game": "a registered octax game id (python -m octax_gym list)",
    "total_steps": "env steps over all envs, per seed (rounded down to whole updates)",
    "num_envs": "parallel training envs per seed",
    "num_steps": "rollout length per env and update",
    "update_epochs": "passes over each rollout",
    "num_minibatches": "Adam steps per epoch (num_envs * num_steps must divide)",
    "learning_rate": "Adam step size",
    "anneal_lr": "decay the learning rate linearly to 0 (the paper: constant)",
    "gamma": "discount",
    "max_grad_norm": "global gradient-norm clip",
    "seed": "the first seed: seeds the network, the envs and the evaluations",
    "num_seeds": "agents trained at once in one program, seeds seed .. seed + num_seeds - 1",
    "eval_every": "env steps between evaluations; 0: only at the start and the end",
    "eval_envs": "evaluation episodes (one per env) per seed, played to their end",
    "eval_max_steps": "step cap per evaluation; None: the env's max_episode_steps",
    "checkpoint_every": "write a resumable checkpoint (every seed's runner: params, optimizer and env state, "
                        "keys; the log so far) every N updates to <out-dir>/resume/; 0: none. --resume "
                        "<out-dir> continues a killed run to the params an uninterrupted one ends with",
    "devices": "'all': data-parallel, every seed's envs split over every device of every process (with "
               "--coordinator, --num-processes, --process-id for several processes), gradients averaged by "
               "the compiled update; '': one device",
    "save_at_evals": "also write the params at every evaluation, as checkpoints/params-step<N>[-seed<S>].msgpack "
                     "(the dataset suite's medium policies come from these)",
}
ENV_FLAGS = {"max_episode_steps": int, "frames_per_step": int, "repeat_action_probability": float,
             "noop_max": int}


def parse_args(config_type: type, help_text: dict, description: str, runs_dir: str,
               argv: Optional[Sequence[str]] = None, loop_flags: bool = False):
    """A `config_type` (a `RunConfig` dataclass) and the output folder from the command line:
    one flag per field, plus the env overrides of ENV_FLAGS and `--out-dir`.

    `loop_flags`: also offer what `train`'s loop does (`--save-at-evals`, `--checkpoint-every`,
    `--resume DIR`) and return (config, out_dir, resume); examples with loops of their own leave
    them out, so no flag does nothing. With `--resume DIR` the config is DIR's config.json.
    """
    parser = argparse.ArgumentParser(description=description,
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    helps = {**HELP, **help_text}
    for field in dataclasses.fields(config_type):
        if field.name == "env_overrides" or (field.name in LOOP_FIELDS and not loop_flags):
            continue
        flag = "--" + field.name.replace("_", "-")
        if field.type in ("bool", bool):
            parser.add_argument(flag, action=argparse.BooleanOptionalAction, default=field.default,
                                help=helps[field.name])
        elif field.name == "eval_max_steps":
            parser.add_argument(flag, type=int, default=None, help=helps[field.name])
        else:
            parser.add_argument(flag, type=type(field.default), default=field.default, help=helps[field.name])
    for name, kind in ENV_FLAGS.items():
        parser.add_argument("--" + name.replace("_", "-"), type=kind, default=None,
                            help="octax_core.make override; None: the game's")
    parser.add_argument("--out-dir", type=Path, default=None,
                        help="for progress.csv, learning_curve.png and the params; "
                             f"None: {runs_dir}/<game>-s<seed>[-n<num_seeds>]")
    if loop_flags:
        parser.add_argument("--coordinator", default=None, metavar="HOST:PORT",
                            help="with --devices all over several processes: process 0's address "
                                 "(octax_gym.distributed.initialize; without it, SLURM or torchrun-style variables)")
        parser.add_argument("--num-processes", type=int, default=None, help="processes in the run")
        parser.add_argument("--process-id", type=int, default=None, help="this process's rank")
        parser.add_argument("--resume", type=Path, default=None, metavar="DIR",
                            help="continue the run in DIR (made with --checkpoint-every) from its last checkpoint, "
                                 "with DIR's config.json; other flags are ignored")
    args = vars(parser.parse_args(argv))
    resume = args.pop("resume", None)
    distributed = [args.pop(name, None) for name in ("coordinator", "num_processes", "process_id")]
    if any(value is not None for value in distributed):
        import octax_gym.distributed
        octax_gym.distributed.initialize(*distributed)  # before anything computes with JAX
    if resume is not None:
        return load_config(config_type, resume / "config.json"), resume, True
    out_dir = args.pop("out_dir")
    overrides = tuple((k, args.pop(k)) for k in ENV_FLAGS if args[k] is not None)
    for k in ENV_FLAGS:
        args.pop(k, None)
    config = config_type(**args, env_overrides=overrides)
    config.check()
    name = f"{config.game}-s{config.seed}" + (f"-n{config.num_seeds}" if config.num_seeds > 1 else "")
    out_dir = out_dir or Path(runs_dir) / name
    return (config, out_dir, False) if loop_flags else (config, out_dir)


def load_config(config_type: type, path: Path):
    """The config a run wrote to its config.json (`train`), as a `config_type`."""
    if not path.is_file():
        raise SystemExit(f"--resume: no {path.name} in {path.parent} (not a run folder of this example)")
    saved = json.loads(path.read_text())
    fields = {field.name for field in dataclasses.fields(config_type)}
    values = {k: v for k, v in saved.items() if k in fields}
    values["env_overrides"] = tuple(tuple(pair) for pair in values.get("env_overrides", ()))
    config = config_type(**values)
    config.check()
    return config


def main(name: str, config_type: type, make_train: Callable, help_text: dict, doc: str, runs_dir: str,
         argv: Optional[Sequence[str]] = None) -> dict:
    """An example's command line: parses `argv` into a `config_type` (flags described by
    `help_text` and the first paragraph of the example's `doc`), trains `make_train`'s algorithm
    `name` with `train` and returns its summary."""
    config, out_dir, resume = parse_args(config_type, help_text, doc.split("\n\n")[0], runs_dir, argv,
                                         loop_flags=True)
    print(f"{name} on {config.game}: {config}")
    summary = train(config, make_train, out_dir, resume=resume)
    print(f"wrote {summary['csv']} and {summary['png']}")
    return summary
