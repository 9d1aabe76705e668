"""The generalization result of docs/results.md ("Generated games: train vs held-out variants"): the
runs of run.sh read back, scored per variant, normalized, aggregated; writes summary.json and
generalization.png beside this file, and copies each run's progress.csv, config.json, summary.json
and agents (as float16) into a folder of its name here.

    python docs/results/generated-dodger/summarize.py ARCHIVE RUNS

ARCHIVE is the dodger archive the runs trained on (its archive.json: splits and baselines), RUNS
the folder run.sh wrote (multitask/, single-<variant>/).

Normalization, per variant: (return - random) / (reference - random), with `reference_score` (the
archive's beam search over emulator states) and `random_horizon_score` (random play), both over the
archive's 300-step horizon, which is why the evaluations are cut at 300 steps. Not `random_score`:
that is a whole first episode (up to 2,000 steps), a longer horizon than the reference's, and for
some variants above it. Agents' scores are the sampled policy's (the paper's protocol); the
untrained networks of step 0 (the same protocol, a near-uniform policy) are the random check.
Aggregates are the IQM over (agents x variants) with a 95% bootstrap interval over variants
(`octax_gym.scores`' stratified bootstrap with the variants as its runs, each agent a stratum: one
or two agents give no spread over runs); the gap's interval comes from independent bootstraps of
the two IQMs.
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import numpy as np

from octax_gym import scores

HERE = Path(__file__).resolve().parent
REPS = 2000


def read_rows(run: Path) -> list[dict]:
    with open(run / "progress.csv", newline="") as file:
        return list(csv.DictReader(file))


def normalized(games: dict, rows: list[dict], untrained: dict = None) -> dict:
    """{(seed, game): normalized score} of `rows`' sampled returns; with `untrained` ({game: return}),
    that is the random end of the scale instead of the archive's `random_horizon_score`."""
    out = {}
    for row in rows:
        g = games[row["game"]]
        random = g["random_horizon_score"] if untrained is None else untrained[row["game"]]
        out[row["seed"], row["game"]] = (float(row["eval_mean_return"]) - random) / (g["reference_score"] - random)
    return out


def untrained_returns(runs: list[Path]) -> dict:
    """{game: mean sampled return} of every run's step-0 evaluation (its untrained networks: a
    near-uniform policy), over all runs and seeds: random play under the agents' own protocol."""
    returns: dict = {}
    for run in runs:
        for row in read_rows(run):
            if int(row["step"]) == 0:
                returns.setdefault(row["game"], []).append(float(row["eval_mean_return"]))
    return {game: float(np.mean(values)) for game, values in returns.items()}


def interval(matrix) -> dict:
    """The IQM of (agents x variants) `matrix`, its interval over variants (the variants resampled
    within each agent: the population here is the family's variants, and the agents are one or two)."""
    ci = scores.stratified_bootstrap_ci(np.asarray(matrix, np.float64).T, scores.iqm, reps=REPS)
    return {"iqm": ci.point, "ci": [ci.low, ci.high], "shape": list(np.shape(matrix))}


def gap(train, test) -> dict:
    a = scores.bootstrap_distribution(np.asarray(train, np.float64).T, scores.iqm, REPS, seed=0)
    b = scores.bootstrap_distribution(np.asarray(test, np.float64).T, scores.iqm, REPS, seed=1)
    low, high = np.percentile(a - b, [2.5, 97.5])
    return {"gap": scores.iqm(np.asarray(train)) - scores.iqm(np.asarray(test)), "ci": [float(low), float(high)]}


def group(norm: dict, seeds, names) -> list[list[float]]:
    return [[norm[seed, name] for name in names] for seed in seeds]


def copy_runs(runs: Path) -> None:
    """Each run's progress.csv, config.json and summary.json beside this file, in a folder of the run's
    name, and its agents as float16 msgpack (what `octax_gym.jax_policy.load_params` reads back)."""
    import shutil

    import flax.serialization

    for run in sorted(p for p in runs.iterdir() if (p / "progress.csv").is_file()):
        target = HERE / run.name
        (target / "agents").mkdir(parents=True, exist_ok=True)
        for name in ("progress.csv", "config.json", "summary.json"):
            if (run / name).is_file():
                shutil.copy(run / name, target / name)
        for agent in sorted((run / "agents").glob("*.msgpack")):
            params = flax.serialization.msgpack_restore(agent.read_bytes())
            half = _tree_map(lambda x: np.asarray(x, np.float16) if np.asarray(x).dtype == np.float32 else x, params)
            (target / "agents" / agent.name).write_bytes(flax.serialization.msgpack_serialize(half))


def _tree_map(fn, tree):
    return {k: _tree_map(fn, v) for k, v in tree.items()} if isinstance(tree, dict) else fn(tree)


def main(archive: Path, runs: Path) -> dict:
    games = {g["name"]: g for g in json.loads((archive / "archive.json").read_text())["games"] if g["accepted"]}
    singles = sorted(p for p in runs.glob("single-*") if (p / "progress.csv").is_file())
    untrained = untrained_returns([runs / "multitask", *singles])
    out = {"archive": result(games, runs, singles, None),
           "untrained": result(games, runs, singles, untrained),
           "untrained_returns": untrained}
    (HERE / "summary.json").write_text(json.dumps(out, indent=2) + "\n")
    draw(out["archive"], HERE / "generalization.png")
    return out


def result(games: dict, runs: Path, singles: list[Path], untrained) -> dict:
    """The aggregates with one normalization: the archive's random (None) or `untrained` returns."""
    train = [n for n, g in games.items() if g["split"] == "train"]
    test = [n for n, g in games.items() if g["split"] == "test"]
    out: dict = {"archive": {"train": len(train), "test": len(test)}, "normalization":
                 "(return - random) / (reference_score - random), 300-step evaluations; random: "
                 + ("the archive's random_horizon_score" if untrained is None else "the untrained networks' return")}
    rows = read_rows(runs / "multitask")
    last, first = max(int(r["step"]) for r in rows), 0
    final = normalized(games, [r for r in rows if int(r["step"]) == last], untrained)
    start = normalized(games, [r for r in rows if int(r["step"]) == first], untrained)
    seeds = sorted({seed for seed, _ in final})
    multi = {"train": group(final, seeds, train), "test": group(final, seeds, test)}
    out["multitask"] = {"steps": last, "seeds": seeds, "train": interval(multi["train"]),
                        "test": interval(multi["test"]), "gap": gap(multi["train"], multi["test"]),
                        "untrained_train": interval(group(start, seeds, train)),
                        "untrained_test": interval(group(start, seeds, test)),
                        "per_variant": {n: [final[s, n] for s in seeds] for n in train + test},
                        "per_variant_untrained": {n: [start[s, n] for s in seeds] for n in train + test}}
    own, other_train, held_out, per_agent = [], [], [], {}
    for run in singles:
        rows = read_rows(run)
        variant = run.name[len("single-"):]
        last_single = max(int(r["step"]) for r in rows)
        norm = normalized(games, [r for r in rows if int(r["step"]) == last_single], untrained)
        seed = next(iter({s for s, _ in norm}))
        own.append(norm[seed, variant])
        other_train.append([norm[seed, n] for n in train if n != variant])
        held_out.append([norm[seed, n] for n in test])
        per_agent[variant] = {"steps": last_single, "own": norm[seed, variant],
                              "other_train_iqm": scores.iqm(np.asarray([other_train[-1]])),
                              "test_iqm": scores.iqm(np.asarray([held_out[-1]]))}
    if singles:
        out["single"] = {"agents": per_agent, "own": interval([own]), "other_train": interval(other_train),
                         "test": interval(held_out), "gap_own_minus_test": gap([own], held_out),
                         "gap_other_train_minus_test": gap(other_train, held_out)}
    return out


def draw(out: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    bars = [("multi-task:\ntrain", out["multitask"]["train"], "C0"),
            ("multi-task:\nheld-out", out["multitask"]["test"], "C1"),
            ("untrained:\ntrain", out["multitask"]["untrained_train"], "silver"),
            ("untrained:\nheld-out", out["multitask"]["untrained_test"], "gray")]
    if "single" in out:
        bars[2:2] = [("single:\nits own", out["single"]["own"], "C2"),
                     ("single:\nother train", out["single"]["other_train"], "C2"),
                     ("single:\nheld-out", out["single"]["test"], "C3")]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 3.6), gridspec_kw={"width_ratios": [1.3, 1]})
    for i, (label, value, color) in enumerate(bars):
        left.bar(i, value["iqm"], color=color, alpha=0.8)
        left.errorbar(i, value["iqm"], yerr=[[value["iqm"] - value["ci"][0]], [value["ci"][1] - value["iqm"]]],
                      color="black", capsize=3)
    left.set_xticks(range(len(bars)), [b[0] for b in bars], fontsize="x-small")
    left.axhline(0, color="gray", linestyle=":", linewidth=1)
    left.axhline(1, color="gray", linestyle="--", linewidth=1)
    left.set_ylabel("normalized score, IQM (95% CI)", fontsize="small")
    left.set_title("0: random play, 1: the beam-search reference (300 steps)", fontsize="small")
    per_variant = out["multitask"]["per_variant"]
    names = list(per_variant)
    values = [np.mean(per_variant[n]) for n in names]
    before = [np.mean(out["multitask"]["per_variant_untrained"][n]) for n in names]
    right.scatter(range(len(names)), before, marker="x", color="gray", s=14, label="untrained")
    right.scatter(range(len(names)), values, c=["C0" if i < out["archive"]["train"] else "C1"
                                                for i in range(len(names))], s=14, label="trained")
    right.legend(fontsize="x-small")
    right.axvline(out["archive"]["train"] - 0.5, color="gray", linestyle=":")
    right.axhline(0, color="gray", linestyle=":", linewidth=1)
    right.set_xticks([])
    right.set_xlabel(f"variants: {out['archive']['train']} train (blue), {out['archive']['test']} held-out "
                     "(orange, fall = 3)", fontsize="x-small")
    right.set_title("multi-task agents per variant (mean of seeds)", fontsize="small")
    fig.suptitle("PPO on generated dodgers: train vs held-out variants", fontsize="medium")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__.split("\n\n")[1])
    copy_runs(Path(sys.argv[2]))
    print(json.dumps(main(Path(sys.argv[1]), Path(sys.argv[2])), indent=2))
