"""The Markdown tables that docs/results.md shows for a finished `octax-gym train` run, printed from
the run's committed summary.json and progress.csv, so that each number on that page can be traced
to the files beside it (tests/docs/test_results_tables.py checks that the page still prints them).

    python docs/results/tables.py docs/results/cpu-2026-11-28/pqn-plateau4
"""
from __future__ import annotations

import collections
import csv
import json
import sys
from pathlib import Path


def tables(run: Path) -> str:
    """The game table (final evaluation, IQM and CI over seeds, greedy, the last training return of
    each seed, random, normalized IQM), the normalized-IQM line, and the sampled evaluation of each
    seed at every evaluation step."""
    summary = json.loads((run / "summary.json").read_text())
    with open(run / "progress.csv", newline="") as file:
        rows = list(csv.DictReader(file))
    games = list(summary["games"])
    seeds = sorted({int(r["seed"]) for r in rows})
    last_train = collections.defaultdict(dict)
    sampled = collections.defaultdict(dict)
    for r in rows:
        if r["train_episode_return"] not in ("", "nan"):
            last_train[r["game"]][int(r["seed"])] = float(r["train_episode_return"])
        sampled[int(r["step"])][(r["game"], int(r["seed"]))] = float(r["eval_sampled_return"])
    lines = [f"| game | sampled, mean of {len(seeds)} seeds | IQM [95% CI] | greedy | training episodes' return "
             "| random | normalized IQM |", "|---|---|---|---|---|---|---|"]
    for game in games:
        g = summary["games"][game]
        train = " / ".join(f"{last_train[game][s]:.2f}" for s in sorted(last_train[game]))
        lines.append(f"| {game} | {g['mean']:.2f} | {g['iqm']:.2f} [{g['iqm_ci'][0]:.2f}, {g['iqm_ci'][1]:.2f}] "
                     f"| {g['greedy_mean']:.2f} | {train} | {g['random']:.2f} | {g['normalized_iqm']:.2f} |")
    iqm = summary["normalized_iqm"]
    lines += ["", f"Normalized IQM over the {len(games)} games x {len(seeds)} seeds: **{iqm['point']:.3f} "
              f"[{iqm['ci'][0]:.3f}, {iqm['ci'][1]:.3f}]**", ""]
    lines += ["| step | " + " | ".join(games) + " |", "|---|" + "---|" * len(games)]
    for step in sorted(sampled):
        cells = [" / ".join(f"{sampled[step][(game, s)]:.2f}" for s in seeds) for game in games]
        lines.append(f"| {step:,} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


if __name__ == "__main__":
    print(tables(Path(sys.argv[1])))
