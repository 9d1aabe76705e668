"""docs/results.md's CPU tables are the committed runs' own: each run's summary.json is what
`octax_gym.train.report.summarize` makes of its progress.csv (the bootstrap is seeded), and every
table `docs/results/tables.py` prints from those files stands on the page as printed. An edited
number, or a run's files replaced without the page, fails here."""

from __future__ import annotations

import csv
import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "docs" / "results"
RUNS = ["cpu-2026-11-28/ppo-plateau4", "cpu-2026-11-28/pqn-plateau4"]


def _tables_module():
    spec = importlib.util.spec_from_file_location("results_tables", RESULTS / "tables.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _rows(run: Path) -> list[dict]:
    with open(run / "progress.csv", newline="") as file:
        rows = list(csv.DictReader(file))
    return [{**r, "seed": int(r["seed"]), "step": int(r["step"]),
             **{k: float(r[k]) for k in ("eval_mean_return", "eval_greedy_return")}} for r in rows]


@pytest.mark.parametrize("name", RUNS)
def test_the_summary_is_the_runs_rows_summarized(name, tmp_path):
    from octax_gym.train import report

    run = RESULTS / name
    summary = json.loads((run / "summary.json").read_text())
    config = json.loads((run / "config.json").read_text())
    seeds = list(range(config["seed"], config["seed"] + config["num_seeds"]))
    report.write(report.summarize(_rows(run), config["games"], seeds), tmp_path / "summary.json")
    again = json.loads((tmp_path / "summary.json").read_text())  # the run's own timings are not in it
    assert again == {key: summary[key] for key in again}


@pytest.mark.parametrize("name", RUNS)
def test_the_page_shows_the_tables_its_files_print(name):
    page = (ROOT / "docs" / "results.md").read_text()
    printed = _tables_module().tables(RESULTS / name)
    for block in printed.split("\n\n"):
        assert block in page, f"docs/results.md lacks, as printed from {name}:\n{block}"
