"""The one training loop: G games x S seeds of one algorithm, as one compiled program.

    summary = train(config, "runs/ppo")      # progress.csv, learning_curve.png, agents/, summary.json

Each update is the trainer's collect and learn mapped over agents (many.py), compiled once; every `eval_every` steps
(and at both ends) every agent plays its evaluation (evaluate.py), the rows go to progress.csv
(log.py), the figure is redrawn (figure.py) and the agents' params are written (checkpoints.py),
so a run cut short keeps what it did. Every `checkpoint_every` updates the whole run is saved for
`resume=True`, which continues it to the params and rows an uninterrupted run ends with.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
from pathlib import Path
from typing import Optional, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from tqdm import tqdm

from octax_gym.train import figure, report, selfplay
from octax_gym.train.algorithm import make_trainer
from octax_gym.train.checkpoints import Checkpoints, host_values, save_agents
from octax_gym.train.config import TrainConfig
from octax_gym.train.envs import Lanes
from octax_gym.train.evaluate import make_evaluate
from octax_gym.train.log import ProgressLog
from octax_gym.train.many import agent_keys, init_agents, over_agents
from octax_gym.train.parallel import DataParallel
from octax_gym.train.seats import SeatLanes


def train(config: TrainConfig, out_dir, *, roms: Optional[Sequence] = None, progress: bool = True,
          resume: bool = False, eval_roms: Optional[Sequence] = None) -> dict:
    """Trains every agent of `config`; writes config.json, progress.csv, learning_curve.png,
    agents/<game>-seed<s>.msgpack (and, with `save_at_evals`, `<game>-seed<s>-step<N>.msgpack` at every
    evaluation) and summary.json to `out_dir`. Returns the summary (paths, env
    steps/s of all agents together, the rows, the final params per agent, the final statistics).

    Args:
        roms: explicit ROM paths, one per game (for GameSpecs of your own; None: the ROM store's).
        eval_roms: the same for `config.eval_games`.
        resume: continue the run in `out_dir` from its last checkpoint (`checkpoint_every`).
    """
    config.check()
    out_dir = Path(out_dir)
    writer = jax.process_index() == 0  # in a multi-process run, process 0 alone writes files
    if config.selfplay:  # both seats of one two-player game as lanes (seats.py)
        lanes = SeatLanes(config.games, dict(config.env_overrides), config.eval_noop_max, roms)
    else:
        lanes = Lanes(config.games, dict(config.env_overrides), config.eval_noop_max, roms,  # refuses a bad mix
                      config.eval_games, eval_roms)
    out_dir.mkdir(parents=True, exist_ok=True)
    trainer = make_trainer(config, lanes)
    rows = config.agents  # (game, seed) of each evaluation row
    num_agents = len(config.agent_names)
    options = lanes.compiler_options  # every jit that steps the env takes its platform's options
    eval_steps = config.eval_max_steps or int(np.asarray(lanes.eval_params.max_episode_steps).max())
    row_agents = np.asarray(config.row_agents)
    log_columns = {}
    if config.selfplay:  # matches against the eval_opponents, on the host (selfplay.py)
        opponents = config.eval_opponents
        evaluate = selfplay.make_evaluate(lanes, config.eval_envs, eval_steps, opponents)
        log_columns = {"eval_columns": selfplay.eval_columns(opponents),
                       "eval_cells": lambda result, i, game: selfplay.evaluation_cells(result, i, opponents)}
    elif config.multitask or config.eval_games:  # each agent plays several rows' games (its own, the eval_games)
        evaluate_rows = over_agents(make_evaluate(lanes, trainer, config.eval_envs, eval_steps), len(rows),
                                    config.agent_map)
        evaluate = jax.jit(lambda params, keys, games: evaluate_rows(
            jax.tree.map(lambda x: x[row_agents], params), keys, games), compiler_options=options)
    else:
        evaluate = jax.jit(over_agents(make_evaluate(lanes, trainer, config.eval_envs, eval_steps), len(rows),
                                       config.agent_map), compiler_options=options)

    if not resume and writer:
        (out_dir / "config.json").write_text(json.dumps(
            {"command": sys.argv, **dataclasses.asdict(config), "games": config.game_ids,
             "eval_games": config.eval_game_ids}, indent=2, default=str)
            + "\n")
    row_games = np.repeat(np.arange(len(config.games) + len(config.eval_games)), config.num_seeds)  # as config.agents
    if config.multitask:  # lane i of every agent plays game i mod G
        games = [np.arange(config.num_envs) % len(config.games)] * config.num_seeds
        train_keys = agent_keys(config.seeds)[0]
    else:
        games = row_games[:num_agents]  # the trained games' rows come first, one per agent
        train_keys = agent_keys([seed for _, seed in rows[:num_agents]])[0]
    eval_keys = agent_keys([seed for _, seed in rows])[1]
    runner = init_agents(trainer.init, train_keys, games)
    checkpoints = Checkpoints(out_dir / "resume", write=writer)
    start_at = None
    if resume:
        runner, start_at = checkpoints.load(runner)
        print(f"resuming {out_dir} at update {start_at['update']} of {config.num_updates}")
    game_ids = jnp.asarray(row_games, jnp.int32)
    shardings = {}
    if config.devices:
        parallel = DataParallel(config)
        runner = parallel.place(runner)
        eval_keys, game_ids = parallel.replicate(eval_keys), parallel.replicate(game_ids)
        shardings = {"in_shardings": (parallel.shardings(runner), None),
                     "out_shardings": (parallel.shardings(runner), parallel.replicated)}
    compile_start = time.perf_counter()
    # The update takes the trainer's data (offline: the dataset) as an argument shared by every agent.
    update = jax.jit(over_agents(_update(trainer), num_agents, config.agent_map, in_axes=(0, None)), donate_argnums=0,
                     compiler_options=options, **shardings).lower(runner, trainer.data).compile()
    print(f"compiled the {trainer.name} update in {time.perf_counter() - compile_start:.1f} s ({num_agents} "
          f"agent{'s' * (num_agents > 1)} x {config.num_envs} envs x {config.num_steps} steps, "
          f"{config.num_updates} updates)")

    title = (f"{'multi-task ' * config.multitask}{'self-play ' * config.selfplay}{trainer.name}, {len(config.games)} game{'s' * (len(config.games) > 1)} x {config.num_seeds} "
             f"seed{'s' * (config.num_seeds > 1)} ({config.num_envs} envs x {config.num_steps} steps)")
    log = ProgressLog(out_dir, rows, trainer.metric_names, row_agents,
                      keep_until=None if start_at is None else start_at["update"], write=writer,
                      splits=config.row_splits if config.eval_games else None, **log_columns)
    bar = tqdm(total=config.num_updates * config.batch_size * num_agents, unit="step", unit_scale=True,
               disable=not progress or not writer, desc=f"{trainer.name} x{num_agents}")
    if start_at is not None:
        bar.update(start_at["update"] * config.batch_size * num_agents)
    start = time.perf_counter()
    view = config.agent_view(lanes.env.observation_shape[0])  # each seat's planes in self-play

    def evaluated(i, runner, train_s, totals):
        result = jax.device_get(evaluate(runner.params, fold(eval_keys, i), game_ids))
        rows = log.add(i, i * config.batch_size, time.perf_counter() - start, train_s, result, totals,
                       trainer.host_metrics(i))
        save_agents(out_dir, config.agent_names, runner.params, write=writer,
                    step=i * config.batch_size if config.save_at_evals else None, view=view)
        if writer:
            figure.draw(log.rows, config.game_ids, out_dir / "learning_curve.png", title)
        bar.set_postfix(eval=f"{np.mean([r['eval_mean_return'] for r in rows]):.2f}")

    runner, train_s = _updates(config, update, runner, trainer.data, evaluated, checkpoints, start_at, bar)
    bar.close()
    steps_per_s = config.num_updates * config.batch_size * num_agents / train_s
    summary = report.summarize(log.rows, config.game_ids, config.seeds)
    if config.eval_games:  # the same at the end for the games never trained on
        summary["eval"] = report.summarize(log.rows, config.eval_game_ids, config.seeds)
    if writer:
        report.write({**summary, "env_steps_per_s": steps_per_s, "train_s": train_s}, out_dir / "summary.json")
    print(f"training speed: {steps_per_s:,.0f} env steps/s of {num_agents} agent(s) together "
          f"(rollout, targets and epochs; compile and evaluation excluded); wall {time.perf_counter() - start:.0f} s")
    print(report.table(summary))
    if config.eval_games:
        print("games never trained on (eval_games):\n" + report.table(summary["eval"]))
    return {**summary, "out_dir": out_dir, "csv": log.csv_path, "png": out_dir / "learning_curve.png",
            "agent_paths": [out_dir / "agents" / f"{name}.msgpack" for name in config.agent_names],
            "env_steps_per_s": steps_per_s, "train_s": train_s, "rows": log.rows,
            "final_params": host_values(runner.params)}


def _update(trainer):
    """One agent's update: its rollout (or its draw from `data`, the trainer's) and targets, then its epochs."""
    def update(runner, data):
        runner, batch, metrics = trainer.collect(runner) if trainer.data is None else trainer.collect(runner, data)
        runner, stats = trainer.learn(runner, batch)
        return runner, {**metrics, **stats}
    return update


fold = jax.jit(jax.vmap(jax.random.fold_in, in_axes=(0, None)))


def _updates(config: TrainConfig, update, runner, data, evaluated, checkpoints: Checkpoints, start_at, bar):
    """The updates, with `evaluated(i, runner, train_s, totals)` every `eval_every` steps and at
    both ends, and a checkpoint every `checkpoint_every` updates. Returns the runner and the
    seconds spent in updates."""
    eval_interval = config.eval_interval
    train_s, totals, first = 0.0, {}, 0
    if start_at is not None:
        first, train_s, totals = start_at["update"], start_at["train_s"], start_at["totals"]
    for i in range(first, config.num_updates + 1):
        resumed_here = start_at is not None and i == first  # its evaluation and checkpoint are on disk
        if (i % eval_interval == 0 or i == config.num_updates) and not resumed_here:
            evaluated(i, runner, train_s, totals)
            totals = {}
        if i == config.num_updates:
            return runner, train_s
        if config.checkpoint_every and i % config.checkpoint_every == 0 and i > 0 and not resumed_here:
            checkpoints.save(runner, {"update": i, "train_s": train_s, "totals": totals})
        t0 = time.perf_counter()
        runner, metrics = update(runner, data)
        metrics = jax.device_get(metrics)  # waits for the update: the timing covers all of it
        train_s += time.perf_counter() - t0
        for k, v in metrics.items():
            totals[k] = totals.get(k, 0.0) + np.asarray(v, np.float64)
        totals["updates"] = totals.get("updates", 0) + 1
        bar.update(config.batch_size * len(config.agent_names))
    return runner, train_s
