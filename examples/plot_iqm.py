"""Normalized IQM learning curves across games and seeds, from the JAX examples' run folders.

    python examples/plot_iqm.py docs/results/jax-pqn-airplane docs/results/jax-pqn-deep8 \
        docs/results/jax-airplane docs/results/jax-deep8 --out docs/results/iqm.png

Each folder holds a run's config.json (its algorithm and game) and progress.csv (one row per seed
and evaluation). Runs are grouped by algorithm; at every evaluation step the runs of a group share,
each seed's return is normalized with the game's committed random and reference scores
(`octax_gym.scores.normalized_score`: 0 is random play, 1 the reference), and the curve is their
interquartile mean across seeds and games with a 95% stratified-bootstrap interval (seeds
resampled within each game). Prints one line per group and evaluation.
"""

from __future__ import annotations

import argparse
import csv
import json
from collections import defaultdict
from pathlib import Path
from typing import Optional, Sequence

import numpy as np

from octax_gym.scores import iqm, normalized_matrix, stratified_bootstrap_ci


def load_run(folder: Path) -> tuple[str, str, dict[int, list[float]]]:
    """(algorithm, game id, {step: [eval return of each seed]}) of one run folder."""
    config = json.loads((folder / "config.json").read_text())
    returns: dict[int, list[float]] = defaultdict(list)
    with open(folder / "progress.csv") as f:
        for row in csv.DictReader(f):
            returns[int(row["step"])].append(float(row["eval_mean_return"]))
    return config["algorithm"], config.get("env_id") or config["game"], dict(returns)


def curves(folders: Sequence[Path], reps: int = 2000) -> dict[str, list[tuple[int, object]]]:
    """Per algorithm: [(step, Interval of the normalized IQM)] over the steps all its runs have."""
    groups: dict[str, list[tuple[str, dict[int, list[float]]]]] = defaultdict(list)
    for folder in folders:
        algorithm, game, returns = load_run(Path(folder))
        groups[algorithm].append((game, returns))
    result = {}
    for algorithm, runs in groups.items():
        games = [game for game, _ in runs]
        if len(set(games)) != len(games):
            raise ValueError(f"{algorithm}: one run folder per game, got {games} (put a game's seeds in one run)")
        seeds = {len(returns[min(returns)]) for _, returns in runs}
        if len(seeds) != 1:
            raise ValueError(f"{algorithm}: every game needs the same number of seeds, got {sorted(seeds)}")
        steps = sorted(set.intersection(*(set(returns) for _, returns in runs)))
        result[algorithm] = []
        for step in steps:
            matrix = np.array([returns[step] for _, returns in runs]).T  # (seeds, games)
            normalized = normalized_matrix(games, matrix)
            result[algorithm].append((step, stratified_bootstrap_ci(normalized, iqm, reps=reps)))
    return result


def plot(result: dict, out: Path, title: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    for algorithm, points in result.items():
        steps = np.array([step for step, _ in points])
        ax.plot(steps, [i.point for _, i in points], "o-", label=f"{algorithm}, IQM")
        ax.fill_between(steps, [i.low for _, i in points], [i.high for _, i in points], alpha=0.2,
                        label=f"{algorithm}, 95% stratified bootstrap")
    ax.axhline(0.0, color="gray", linestyle=":", label="random play")
    ax.axhline(1.0, color="gray", linestyle="--", label="reference score")
    ax.set_xlabel("env steps (per seed)")
    ax.set_ylabel("normalized return")
    ax.set_title(title)
    ax.legend(loc="best", fontsize="small")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)


def main(argv: Optional[Sequence[str]] = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="run folders (config.json + progress.csv)")
    parser.add_argument("--out", type=Path, default=Path("iqm.png"), help="the figure")
    parser.add_argument("--reps", type=int, default=2000, help="bootstrap resamples")
    args = parser.parse_args(argv)
    result = curves(args.runs, args.reps)
    for algorithm, points in result.items():
        for step, interval in points:
            print(f"{algorithm} step={step} normalized_iqm={interval.point:.3f} "
                  f"ci95=[{interval.low:.3f}, {interval.high:.3f}]")
    games = sorted({load_run(Path(folder))[1] for folder in args.runs})
    plot(result, args.out, f"Normalized IQM over {', '.join(games)}")
    print(f"wrote {args.out}")
    return result


if __name__ == "__main__":
    main()
