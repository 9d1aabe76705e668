"""progress.csv: one row per (game, seed, evaluation), appended as the run goes.

Columns: the agent (`game`, `seed`), where the run is (`step` per agent, `update`, `wall_s`,
`env_steps_per_s` of all agents together, compile and evaluation excluded), the evaluation
(`eval_mean_return` is the sampled policy's, the paper's protocol; `eval_greedy_*` and
`eval_sampled_*` both, with their std over episodes; `eval_ended_frac`), the random baseline and
the normalized score from the committed table (`octax_gym.scores`: never re-measured here), the
training episodes finished since the last evaluation, and the algorithm's metrics averaged over
those updates. A resumed run rewrites the file with the rows up to its checkpoint.

A run with `eval_games` (games its agents never train on) has a `split` column after `seed`: "train"
for a row of a game the agent trains on, "eval" for one of those.

A self-play run's evaluation columns are its matches' (selfplay.py's `eval_columns`: win, draw,
loss and margin against each opponent, greedy and sampled) in place of the one-player ones
(`EVAL_COLUMNS` here); the other columns are the same.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Callable, Optional, Sequence

import numpy as np

from octax_gym import scores

HEAD_COLUMNS = ("game", "seed", "step", "update", "wall_s", "env_steps_per_s")
EVAL_COLUMNS = ("eval_mean_return", "eval_std", "eval_greedy_return", "eval_greedy_std", "eval_sampled_return",
                "eval_sampled_std", "eval_ended_frac", "random_mean_return", "normalized_score")
TRAIN_COLUMNS = ("train_episode_return", "train_episodes")
COMMON_COLUMNS = HEAD_COLUMNS + EVAL_COLUMNS + TRAIN_COLUMNS


def baseline(game: str) -> tuple[float, Optional[float]]:
    """The game's random mean return and reference from `octax_gym/data/scores.json`; (nan, None)
    for a game the table does not list (a GameSpec of your own)."""
    row = scores.score_table().get(game)
    return (math.nan, None) if row is None else (row.random_mean, row.reference)


def normalized(game: str, value: float) -> float:
    """(value - random) / (reference - random), or nan where the game has no reference."""
    random_mean, reference = baseline(game)
    if reference is None or math.isnan(random_mean):
        return math.nan
    return float(scores.normalized_score(game, value))


def evaluation_cells(evaluation, i: int, game: str) -> dict:
    """Row `i`'s `EVAL_COLUMNS` from a one-player `Evaluation` of (num_rows, eval_envs) arrays."""
    greedy, sampled = np.asarray(evaluation.greedy_return[i]), np.asarray(evaluation.sampled_return[i])
    ended = np.concatenate([np.asarray(evaluation.greedy_ended[i]), np.asarray(evaluation.sampled_ended[i])])
    mean = float(sampled.mean())
    return {"eval_mean_return": mean, "eval_std": float(sampled.std()),
            "eval_greedy_return": float(greedy.mean()), "eval_greedy_std": float(greedy.std()),
            "eval_sampled_return": mean, "eval_sampled_std": float(sampled.std()),
            "eval_ended_frac": float(ended.mean()), "random_mean_return": baseline(game)[0],
            "normalized_score": normalized(game, mean)}


class ProgressLog:
    """Appends the rows of each evaluation to `out_dir/progress.csv`."""

    def __init__(self, out_dir: Path, agents: Sequence[tuple[str, int]], metric_names: Sequence[str],
                 row_agents: Sequence[int], keep_until: Optional[int] = None, write: bool = True,
                 eval_columns: Sequence[str] = EVAL_COLUMNS, eval_cells: Callable = evaluation_cells,
                 splits: Optional[Sequence[str]] = None):
        """A new log of a row per (game, seed) of `agents`, each played by agent `row_agents[i]`
        (training statistics are that agent's); or, with `keep_until` (a resumed run's update),
        the existing rows up to that update, rewritten without the rows a killed run logged after
        its checkpoint. `eval_cells(evaluation, i, game)` gives row i's `eval_columns`; `splits`, each
        row's split ("train" or "eval"), adds the `split` column."""
        self.csv_path = Path(out_dir) / "progress.csv"
        self.agents, self.metric_names, self.rows, self.write = list(agents), tuple(metric_names), [], write
        self.row_agents, self.eval_cells = list(row_agents), eval_cells
        self.splits = None if splits is None else list(splits)
        head = HEAD_COLUMNS if splits is None else HEAD_COLUMNS[:2] + ("split",) + HEAD_COLUMNS[2:]
        self.columns = head + tuple(eval_columns) + TRAIN_COLUMNS + self.metric_names
        if not write:
            return
        if keep_until is not None:
            with open(self.csv_path, newline="") as f:
                self.rows = [{k: _cell(k, v) for k, v in row.items()} for row in csv.DictReader(f)
                             if int(row["update"]) <= keep_until]
        with open(self.csv_path, "w", newline="") as f:
            csv.writer(f).writerow(self.columns)
            csv.DictWriter(f, self.columns).writerows(self.rows)

    def add(self, update: int, step: int, wall_s: float, train_s: float, evaluation, totals: dict,
            host_metrics: dict) -> list[dict]:
        """Rows for one evaluation: `evaluation` what `eval_cells` reads (an `Evaluation` of
        (num_rows, eval_envs) arrays); `totals` each metric's (num_agents,) sum over the updates
        since the last evaluation."""
        n = totals.get("updates", 0)
        rows = []
        num_agents = len(set(self.row_agents))
        for i, (game, seed) in enumerate(self.agents):
            a = self.row_agents[i]
            episodes = float(totals["finished_episodes"][a]) if n else 0.0
            split = {} if self.splits is None else {"split": self.splits[i]}
            row = {"game": game, "seed": seed, **split, "step": step, "update": update, "wall_s": round(wall_s, 2),
                   "env_steps_per_s": round(step * num_agents / train_s, 1) if train_s else math.nan,
                   **self.eval_cells(evaluation, i, game),
                   "train_episode_return": (float(totals["finished_return_sum"][a]) / episodes
                                            if episodes else math.nan),
                   "train_episodes": int(episodes)}
            for name in self.metric_names:
                row[name] = float(totals[name][a]) / n if n and name in totals else host_metrics.get(name, math.nan)
            rows.append(row)
        self.rows.extend(rows)
        if self.write:
            with open(self.csv_path, "a", newline="") as f:
                csv.DictWriter(f, self.columns).writerows(rows)
        return rows


def _cell(column: str, text: str):
    """A CSV cell back as the value it was written from."""
    if column in ("game", "split"):
        return text
    try:
        return int(text)
    except ValueError:
        return float(text)
