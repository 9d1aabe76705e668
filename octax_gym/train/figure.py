"""The learning-curve figure in the paper's layout: one panel per game, each the mean evaluation
return over seeds with its bootstrap confidence band, and the random baseline.

The band is the 95% percentile interval of the mean over seeds (`octax_gym.scores`, resampling
seeds with replacement; 200 resamples per point: the figure is redrawn at every evaluation, and
its band is a picture, not a reported number; report.py's intervals use 2000).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import numpy as np

from octax_gym import scores

BAND_REPS = 200


def draw(rows: Sequence[dict], games: Sequence[str], path: Path, title: str) -> None:
    """Draws progress.csv's `rows` for `games` to `path` (PNG)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = min(4, len(games))
    nrows = math.ceil(len(games) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(3.6 * cols, 2.8 * nrows), squeeze=False)
    for ax, game in zip(axes.flat, games):
        _panel(ax, [r for r in rows if r["game"] == game], game)
    for ax in list(axes.flat)[len(games):]:
        ax.axis("off")
    fig.suptitle(title, fontsize="medium")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _panel(ax, rows: Sequence[dict], game: str) -> None:
    steps = sorted({r["step"] for r in rows})
    by_step = [np.array([r["eval_mean_return"] for r in rows if r["step"] == s], np.float64) for s in steps]
    mean = np.array([v.mean() for v in by_step])
    ax.plot(steps, mean, "-", color="C0", label="mean over seeds")
    if max((len(v) for v in by_step), default=0) > 1:
        bands = [scores.stratified_bootstrap_ci(v, scores.mean, reps=BAND_REPS) for v in by_step]
        ax.fill_between(steps, [b.low for b in bands], [b.high for b in bands], color="C0", alpha=0.25,
                        label="95% CI")
    random_mean = rows[0].get("random_mean_return", math.nan) if rows else math.nan  # self-play rows have none
    if not math.isnan(random_mean):
        ax.axhline(random_mean, color="gray", linestyle=":", label="random")
    ax.set_title(game, fontsize="small")
    ax.tick_params(labelsize="x-small")
    ax.set_xlabel("env steps", fontsize="x-small")
