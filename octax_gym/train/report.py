"""The run's results at its end: per game the final evaluation over seeds, and across games the
IQM of normalized scores, each with a stratified bootstrap 95% interval (`octax_gym.scores`,
Agarwal et al. 2021, as the paper reports them). Written to `summary.json` and printed.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Sequence

import numpy as np

from octax_gym import scores
from octax_gym.train.log import baseline, normalized

REPS = 2000


def summarize(rows: Sequence[dict], games: Sequence[str], seeds: Sequence[int]) -> dict:
    """Per game: the last evaluation's sampled and greedy returns over seeds (mean, IQM and its
    interval), the random baseline and the normalized IQM; overall: the IQM of the normalized
    final scores (seeds x games) and its interval, where every game has a reference."""
    last = max(r["step"] for r in rows)
    final = [r for r in rows if r["step"] == last]
    per_game, matrix = {}, []
    for game in games:
        sampled = np.array([_of(final, game, s, "eval_mean_return") for s in seeds])
        greedy = np.array([_of(final, game, s, "eval_greedy_return") for s in seeds])
        interval = scores.stratified_bootstrap_ci(sampled, scores.iqm, reps=REPS)
        random_mean, reference = baseline(game)
        per_game[game] = {"step": last, "returns": sampled.tolist(), "greedy_returns": greedy.tolist(),
                          "mean": float(sampled.mean()), "greedy_mean": float(greedy.mean()),
                          "iqm": interval.point, "iqm_ci": [interval.low, interval.high],
                          "random": random_mean, "reference": reference,
                          "normalized_iqm": normalized(game, interval.point)}
        matrix.append([normalized(game, v) for v in sampled])
    out = {"games": per_game}
    matrix = np.array(matrix, np.float64).T  # (seeds, games)
    scored = [i for i in range(len(games)) if matrix.size and not np.isnan(matrix[:, i]).any()]
    if scored:  # games without a reference score (Tetris) have no normalized score: left out, and named
        interval = scores.stratified_bootstrap_ci(matrix[:, scored], scores.iqm, reps=REPS)
        out["normalized_iqm"] = {"point": interval.point, "ci": [interval.low, interval.high],
                                 "games": [games[i] for i in scored],
                                 "left_out": [g for i, g in enumerate(games) if i not in scored]}
    return out


def write(summary: dict, path: Path) -> None:
    """Strict JSON: a score that is not a number (a game without a reference score) is null."""
    Path(path).write_text(json.dumps(_finite(summary), indent=2, default=_plain, allow_nan=False) + "\n")


def _finite(x):
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if isinstance(x, (float, np.floating)) and not math.isfinite(float(x)):
        return None
    return x


def table(summary: dict) -> str:
    """The summary as a text table, one line per game."""
    lines = [f"{'game':<14} {'mean':>8} {'IQM [95% CI]':>24} {'greedy':>8} {'random':>7} {'norm.':>6}"]
    for game, g in summary["games"].items():
        ci = f"{g['iqm']:.2f} [{g['iqm_ci'][0]:.2f}, {g['iqm_ci'][1]:.2f}]"
        lines.append(f"{game:<14} {g['mean']:>8.2f} {ci:>24} {g['greedy_mean']:>8.2f} {g['random']:>7.2f} "
                     f"{_num(g['normalized_iqm']):>6}")
    if "normalized_iqm" in summary:
        n = summary["normalized_iqm"]
        over = "all runs" if not n["left_out"] else f"the games with a reference score (not {', '.join(n['left_out'])})"
        lines.append(f"normalized IQM over {over}: {n['point']:.3f} [{n['ci'][0]:.3f}, {n['ci'][1]:.3f}]")
    return "\n".join(lines)


def _of(rows, game, seed, column) -> float:
    return next(r[column] for r in rows if r["game"] == game and r["seed"] == seed)


def _num(x) -> str:
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.2f}"


def _plain(x):
    return float(x) if isinstance(x, (np.floating, np.integer)) else str(x)
