"""Offline RL baselines on the dataset suite, in pure JAX: behaviour cloning and discrete CQL.

    python examples/train_offline.py --algorithm bc --kind expert            # every suite game
    python examples/train_offline.py --algorithm cql --kind medium --games Airplane Flak --num-seeds 3
    python examples/train_offline.py --algorithm bc --dataset-id octax/Flak/expert-v0   # any dataset

Each dataset is loaded once into flat transitions on JAX's device (`octax_gym.datasets.
load_transitions`); training is `lax.scan` over gradient steps, each drawing a minibatch with
`Transitions.sample` inside the compiled program (no Python per step), vmapped over seeds. Both
use the PQN example's network (examples/jax_networks.py `QNetwork`: the paper's CNN torso, a
256-unit LayerNorm layer, one output per action):

- bc: the outputs are logits; cross-entropy with the dataset's actions.
- cql: the outputs are Q-values; a DQN loss (Huber, target network copied every `--target-every`
  steps) plus CQL's regulariser alpha * (logsumexp_a Q(s, a) - Q(s, a_data)) (Kumar et al., 2020,
  the discrete-action form they used on Atari).

Each trained agent then plays `--eval-envs` episodes greedily in the batched env the dataset was
collected in (its recovered env options: the suite caps episodes at 2000 steps). Scores are
normalized with `octax_gym.scores` (random 0, reference 1), and the IQM over games x seeds comes
with a stratified-bootstrap 95% interval (`octax_gym.scores.aggregate`). Writes `results.csv` (one
row per game and seed) and `summary.json` to `--out-dir`. See docs/datasets.md.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import sys
import time
from pathlib import Path
from typing import Optional, Sequence

import jax
import jax.numpy as jnp
import numpy as np
import optax

import octax_core
from jax_networks import QNetwork
from jax_training import make_evaluate
from octax_gym import scores
from octax_gym.datasets import load_transitions
from octax_gym.datasets.storage import import_minari
from octax_gym.datasets.suite import GAMES, dataset_id

ALGORITHMS = ("bc", "cql")


def make_learner(algorithm: str, num_actions: int, args):
    """(init(key) -> state, step(state, data, key) -> (state, loss)) for one seed."""
    network = QNetwork(num_actions)
    optimizer = optax.chain(optax.clip_by_global_norm(10.0), optax.adam(args.learning_rate))

    def init(key):
        params = network.init(key, jnp.zeros((1, 4, 32, 64), jnp.uint8))
        return {"params": params, "target": params, "opt": optimizer.init(params), "step": jnp.int32(0)}

    def loss_fn(params, target, batch):
        out = network.apply(params, batch.obs)
        if algorithm == "bc":
            return optax.softmax_cross_entropy_with_integer_labels(out, batch.action).mean()
        q_taken = jnp.take_along_axis(out, batch.action[:, None], 1)[:, 0]
        next_q = network.apply(target, batch.next_obs).max(-1)
        td_target = batch.reward + args.gamma * (1.0 - batch.terminated.astype(jnp.float32)) * next_q
        td = optax.huber_loss(q_taken, jax.lax.stop_gradient(td_target)).mean()
        conservative = (jax.nn.logsumexp(out, axis=-1) - q_taken).mean()
        return td + args.cql_alpha * conservative

    def step(state, data, key):
        batch = data.sample(key, args.batch_size)
        loss, grads = jax.value_and_grad(loss_fn)(state["params"], state["target"], batch)
        updates, opt = optimizer.update(grads, state["opt"], state["params"])
        params = optax.apply_updates(state["params"], updates)
        count = state["step"] + 1
        target = jax.tree.map(lambda t, p: jnp.where(count % args.target_every == 0, p, t), state["target"], params)
        return {"params": params, "target": target, "opt": opt, "step": count}, loss

    def act(params, key, obs):
        return jnp.argmax(network.apply(params, obs), axis=-1)

    return init, step, act


def run_dataset(algorithm: str, ident: str, args) -> dict:
    """Trains `args.num_seeds` agents on one dataset and evaluates them; returns the game's rows."""
    minari = import_minari()
    dataset = minari.load_dataset(ident)
    game = dataset.spec.env_spec.kwargs["game"]
    options = {k: v for k, v in dataset.spec.env_spec.kwargs.items() if k != "game"}
    started = time.perf_counter()
    data = load_transitions(dataset).device_put()
    load_s = time.perf_counter() - started
    num_actions = int(dataset.action_space.n)
    init, step, act = make_learner(algorithm, num_actions, args)
    seeds = jnp.arange(args.seed, args.seed + args.num_seeds)

    def train_chunk(states, data, keys):  # keys: (steps, seeds)
        def body(states, keys):
            return jax.vmap(step, in_axes=(0, None, 0))(states, data, keys)
        return jax.lax.scan(body, states, keys)

    train_chunk = jax.jit(train_chunk)
    states = jax.vmap(lambda s: init(jax.random.key(s)))(seeds)
    keys = jax.vmap(lambda s: jax.random.split(jax.random.fold_in(jax.random.key(s), 1), args.steps))(seeds)
    keys = jnp.swapaxes(keys, 0, 1)
    chunk = max(1, min(args.log_every, args.steps))
    started = time.perf_counter()
    for first in range(0, args.steps, chunk):
        states, losses = train_chunk(states, data, keys[first:first + chunk])
        print(f"  {game} {algorithm}: step {min(first + chunk, args.steps):,}/{args.steps:,}, "
              f"loss {np.asarray(losses[-1]).mean():.4f}", flush=True)
    train_s = time.perf_counter() - started

    env, env_params = octax_core.make(game, autoreset=False, **options)
    evaluate = make_evaluate(env, env_params, args.eval_envs, int(env_params.max_episode_steps), act, jit=False)
    evaluate = jax.jit(jax.vmap(evaluate), compiler_options=env.compiler_options)
    returns, ended = jax.device_get(evaluate(states["params"], jax.vmap(lambda s: jax.random.key(10_000 + s))(seeds)))
    random_eval = jax.jit(make_evaluate(env, env_params, args.eval_envs, int(env_params.max_episode_steps),
                                        lambda _, key, obs: jax.random.randint(key, obs.shape[:1], 0, num_actions),
                                        jit=False), compiler_options=env.compiler_options)
    random_return = float(jax.device_get(random_eval(None, jax.random.key(99))[0]).mean())
    dataset_return = float(np.mean([e.rewards.sum() for e in dataset.iterate_episodes()]))
    rows = []
    for i, seed in enumerate(np.asarray(seeds)):
        mean = float(returns[i].mean())
        rows.append({"game": game, "dataset_id": ident, "algorithm": algorithm, "seed": int(seed),
                     "return": mean, "ended_frac": float(ended[i].mean()),
                     "normalized": float(scores.normalized_score(game, mean)),
                     "dataset_return": dataset_return, "random_return": random_return,
                     "steps": args.steps, "batch_size": args.batch_size, "load_s": round(load_s, 2),
                     "train_s": round(train_s, 1), "dataset_steps": len(data)})
    per_seed = ", ".join(f"{row['return']:.2f}" for row in rows)
    print(f"{ident} {algorithm}: return {np.mean(returns):.2f} (seeds: {per_seed}); dataset {dataset_return:.2f}, random {random_return:.2f}; "
          f"{len(data):,} transitions loaded in {load_s:.1f} s, {args.steps:,} steps x {args.num_seeds} seeds "
          f"in {train_s:.0f} s", flush=True)
    return rows


def parse_args(argv: Optional[Sequence[str]] = None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--algorithm", choices=ALGORITHMS, required=True)
    parser.add_argument("--kind", default="expert", choices=("random", "medium", "expert"),
                        help="the suite datasets to train on")
    parser.add_argument("--games", nargs="+", default=list(GAMES), help="suite games")
    parser.add_argument("--dataset-id", nargs="+", default=None,
                        help="train on these Minari dataset ids instead of the suite's")
    parser.add_argument("--steps", type=int, default=2000, help="gradient steps per seed")
    parser.add_argument("--batch-size", type=int, default=128)
    parser.add_argument("--learning-rate", type=float, default=3e-4)
    parser.add_argument("--gamma", type=float, default=0.99)
    parser.add_argument("--cql-alpha", type=float, default=1.0, help="CQL regulariser weight")
    parser.add_argument("--target-every", type=int, default=500, help="CQL target network copy period (steps)")
    parser.add_argument("--num-seeds", type=int, default=2, help="agents per dataset, trained at once")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--eval-envs", type=int, default=32, help="evaluation episodes per agent")
    parser.add_argument("--log-every", type=int, default=500, help="gradient steps per compiled chunk")
    parser.add_argument("--out-dir", type=Path, default=None, help="default runs/offline/<algorithm>-<kind>")
    parser.add_argument("--summarize", nargs="+", type=Path, default=None, metavar="CSV",
                        help="train nothing: the IQM summary of earlier runs' results.csv files (one game "
                             "per file or several), written to --out-dir")
    args = parser.parse_args(argv)
    for name in ("steps", "batch_size", "num_seeds", "eval_envs", "log_every", "target_every"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be >= 1")
    return args


def main(argv: Optional[Sequence[str]] = None) -> dict:
    args = parse_args(argv)
    out_dir = args.out_dir or Path("runs/offline") / f"{args.algorithm}-{args.kind}"
    out_dir.mkdir(parents=True, exist_ok=True)
    if args.summarize:
        rows = []
        for path in args.summarize:
            with open(path, newline="") as file:
                rows += [{**row, "normalized": float(row["normalized"])} for row in csv.DictReader(file)
                         if row["algorithm"] == args.algorithm]
        if not rows:
            raise SystemExit(f"no {args.algorithm} rows in {', '.join(map(str, args.summarize))}")
    else:
        idents = args.dataset_id or [dataset_id(game, args.kind) for game in args.games]
        rows = [row for ident in idents for row in run_dataset(args.algorithm, ident, args)]
    with open(out_dir / "results.csv", "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    games = list(dict.fromkeys(row["game"] for row in rows))
    per_game = [[row["normalized"] for row in rows if row["game"] == game] for game in games]
    if len({len(runs) for runs in per_game}) != 1:
        raise SystemExit(f"every game needs the same number of seeds to aggregate, got {dict(zip(games, map(len, per_game)))}")
    matrix = np.array(per_game).T
    summary = {"algorithm": args.algorithm, "datasets": list(dict.fromkeys(row["dataset_id"] for row in rows)),
               "command": sys.argv,
               "normalized": {game: matrix[:, j].tolist() for j, game in enumerate(games)},
               **{name: dataclasses.asdict(interval) for name, interval in scores.aggregate(matrix).items()}}
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=2, default=float) + "\n")
    iqm = summary["iqm"]
    print(f"{args.algorithm} on {len(games)} games x {args.num_seeds} seeds: normalized IQM {iqm['point']:.3f} "
          f"[{iqm['low']:.3f}, {iqm['high']:.3f}]; wrote {out_dir}/results.csv and summary.json")
    return summary


if __name__ == "__main__":
    main(sys.argv[1:])
