"""octax_gym.scores: the IQM and the stratified bootstrap on cases worked out by hand, the
normalized-score arithmetic, and the committed table (octax_gym/data/scores.json) held to the
registry and to a fresh measurement, so it cannot go stale silently.
"""

from __future__ import annotations

import itertools
import json
import runpy
import subprocess
import sys
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

import octax_core
from octax_core.env.games import suite_of
from octax_gym import scores

DOCS = Path(__file__).resolve().parents[2] / "docs"
REMEASURED = ("Br8kout", "Masquer8")  # shipped archive ROMs whose random episodes end within ~400 steps


@pytest.fixture(scope="module")
def script():
    """docs/scores.py's functions, the ones that made the table."""
    return runpy.run_path(str(DOCS / "scores.py"))


@pytest.fixture(scope="module")
def table():
    return scores.score_table()


# --- IQM and the other statistics -----------------------------------------------------------------


def test_iqm_by_hand():
    # 8 scores: the 2 lowest and 2 highest go, leaving 3, 4, 5, 6.
    assert scores.iqm([[8, 1], [3, 6], [5, 2], [4, 7]]) == 4.5
    # 10 scores (not a multiple of 4): int(10 / 4) = 2 go at each end, leaving 3..8.
    ten = np.array([[10, 1, 9, 2, 8], [3, 7, 4, 6, 5]]).T
    assert scores.iqm(ten) == np.mean([3, 4, 5, 6, 7, 8]) == 5.5
    # 6 scores: int(1.5) = 1 goes at each end; the outlier is gone.
    assert scores.iqm([[1, 2, 100], [3, 4, 5]]) == np.mean([2, 3, 4, 5])
    # 3 scores: int(0.75) = 0, nothing is trimmed.
    assert scores.iqm([1, 2, 6]) == 3.0
    rng = np.random.default_rng(0)
    matrix = rng.normal(size=(7, 5))
    assert scores.iqm(matrix) == pytest.approx(stats.trim_mean(matrix.ravel(), 0.25))


def test_mean_median_and_optimality_gap_by_hand():
    matrix = [[0.0, 1.0, 4.0], [2.0, 3.0, 0.0]]  # per-game means 1, 2, 2
    assert scores.mean(matrix) == pytest.approx(5 / 3)
    assert scores.median(matrix) == 2.0
    # min(score, 1): 0, 1, 1, 1, 1, 0 -> mean 4/6; the gap is 1 - 4/6.
    assert scores.optimality_gap(matrix) == pytest.approx(1 / 3)
    assert scores.optimality_gap(matrix, gamma=2.0) == pytest.approx(2 - np.mean([0, 1, 2, 2, 2, 0]))


def test_bad_matrices_and_settings_raise():
    with pytest.raises(ValueError, match="num_runs, num_games"):
        scores.iqm(np.zeros((2, 2, 2)))
    with pytest.raises(ValueError, match="non-empty"):
        scores.iqm([])
    with pytest.raises(ValueError, match="confidence"):
        scores.stratified_bootstrap_ci([[1.0]], confidence=1.0)
    with pytest.raises(ValueError, match="reps"):
        scores.bootstrap_distribution([[1.0]], reps=0)


# --- the stratified bootstrap ---------------------------------------------------------------------


def test_runs_alike_within_each_game_give_a_zero_width_interval():
    """Every resample of a game whose runs are equal is that game again: no spread at all."""
    matrix = np.array([[1.0, 5.0, -2.0]] * 4)
    for statistic in scores.STATISTICS.values():
        interval = scores.stratified_bootstrap_ci(matrix, statistic, reps=300, seed=3)
        assert interval.low == interval.point == interval.high == statistic(matrix)


def test_bootstrap_is_a_resample_of_runs_within_each_game():
    """Against a direct loop over the documented draws: run i of game j is scores[rows[r, i, j], j]."""
    matrix = np.random.default_rng(11).normal(size=(5, 3))
    reps, seed = 200, 7
    rows = np.random.default_rng(seed).integers(0, 5, (reps, 5, 3))
    expected = []
    for r in range(reps):
        resample = np.empty_like(matrix)
        for i in range(5):
            for j in range(3):
                resample[i, j] = matrix[rows[r, i, j], j]
        expected.append(stats.trim_mean(resample.ravel(), 0.25))
    assert np.array_equal(scores.bootstrap_distribution(matrix, scores.iqm, reps, seed), expected)
    interval = scores.stratified_bootstrap_ci(matrix, scores.iqm, reps, confidence=0.9, seed=seed)
    assert (interval.low, interval.high) == tuple(np.percentile(expected, [5, 95]))
    assert interval.point == scores.iqm(matrix)
    assert scores.stratified_bootstrap_ci(matrix, scores.iqm, reps, seed=seed) == \
        scores.stratified_bootstrap_ci(matrix, scores.iqm, reps, seed=seed)


@pytest.mark.parametrize("shape", [(1, 1), (2, 3), (7, 1), (5, 9), (33, 4)])
def test_the_bootstrap_of_each_statistic_is_that_statistic_of_each_resample(shape):
    """The bootstrap computes the paper's four statistics on the whole stack of resamples at once;
    each value is, to the bit, the statistic of that resample alone (and the IQM scipy's trim_mean,
    NaN included: a resample with a NaN is NaN, even where the NaN would be trimmed)."""
    rng = np.random.default_rng(sum(shape))
    matrix = np.round(rng.normal(size=shape) * 100, 1)  # ties too
    with_nan = matrix.copy()
    with_nan.flat[-1] = np.nan
    reps, seed = 150, 5
    resamples = matrix[np.random.default_rng(seed).integers(0, shape[0], (reps, *shape)), np.arange(shape[1])]
    for name, statistic in scores.STATISTICS.items():
        expected = [statistic(resample) for resample in resamples]
        assert np.array_equal(scores.bootstrap_distribution(matrix, statistic, reps, seed), expected), name
    nan_resamples = with_nan[np.random.default_rng(seed).integers(0, shape[0], (reps, *shape)), np.arange(shape[1])]
    expected = [stats.trim_mean(resample, 0.25, axis=None) for resample in nan_resamples]
    assert np.array_equal(scores.bootstrap_distribution(with_nan, scores.iqm, reps, seed), expected, equal_nan=True)
    assert np.isnan(scores.iqm(with_nan))


def test_a_statistic_of_ones_own_is_called_on_each_resample():
    matrix = np.arange(12.0).reshape(4, 3)
    seen = []

    def spread(resample):
        seen.append(resample.shape)
        return float(resample.max() - resample.min())

    distribution = scores.bootstrap_distribution(matrix, spread, reps=20, seed=1)
    assert seen == [(4, 3)] * 20 and distribution.shape == (20,) and (distribution <= 11).all()


def test_scores_imports_no_scipy():
    """`from scipy import stats` cost a second of every training process's start; numpy does it."""
    probe = ("import sys, octax_gym.scores, octax_gym.train.report\n"
             "print(sorted(m for m in sys.modules if m.startswith('scipy')))")
    assert subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout == "[]\n"


def test_bootstrap_reaches_exactly_the_enumerated_resamples():
    """2 runs x 2 games: 4 x 4 equally likely resamples; the bootstrap's values are exactly theirs,
    never one that mixes the games, and their frequencies match the enumeration's."""
    matrix = np.array([[0.0, 10.0], [1.0, 30.0]])
    per_game = [list(itertools.product(matrix[:, j], repeat=2)) for j in range(2)]
    enumerated = [np.mean(a + b) for a, b in itertools.product(*per_game)]
    distribution = scores.bootstrap_distribution(matrix, scores.mean, reps=4000, seed=0)
    assert set(distribution) == set(enumerated)
    standard_error = np.std(enumerated) / np.sqrt(4000)
    assert abs(distribution.mean() - np.mean(enumerated)) < 4 * standard_error
    for value in set(enumerated):  # each value's frequency within 4 standard errors of its probability
        p = enumerated.count(value) / len(enumerated)
        assert abs(np.mean(distribution == value) - p) < 4 * np.sqrt(p * (1 - p) / 4000)


def test_aggregate_gives_the_four_statistics_with_intervals():
    matrix = np.random.default_rng(2).uniform(size=(6, 4))
    results = scores.aggregate(matrix, reps=100, seed=1)
    assert list(results) == ["iqm", "mean", "median", "optimality_gap"]
    for name, interval in results.items():
        assert interval.point == scores.STATISTICS[name](matrix)
        assert interval.low <= interval.high


# --- normalized scores ----------------------------------------------------------------------------


def test_normalized_score_arithmetic(table):
    game_id = next(g for g, row in table.items() if row.has_reference)
    row = table[game_id]
    assert scores.normalized_score(game_id, row.random_mean) == 0.0
    assert scores.normalized_score(game_id, row.reference) == pytest.approx(1.0)
    span = row.reference - row.random_mean
    values = np.array([row.random_mean - span, row.random_mean + 2.5 * span])
    assert np.allclose(scores.normalized_score(game_id, values), [-1.0, 2.5])
    assert isinstance(scores.normalized_score(game_id, 3), float)
    both = next(g for g, r in table.items() if r.has_reference and g != game_id)
    matrix = scores.normalized_matrix([game_id, both], [[row.reference, table[both].random_mean]] * 3)
    assert np.allclose(matrix, [[1.0, 0.0]] * 3)
    with pytest.raises(ValueError, match="columns"):
        scores.normalized_matrix([game_id], [[1.0, 2.0]])


def test_no_normalized_score_without_a_reference(table):
    game_id = next(g for g, row in table.items() if not row.has_reference)
    with pytest.raises(ValueError, match="has no normalized score"):
        scores.normalized_score(game_id, 1.0)
    with pytest.raises(KeyError, match="unknown scored game 'NoSuchGame'; valid: 'Airplane'"):
        scores.normalized_score("NoSuchGame", 1.0)


# --- the committed table --------------------------------------------------------------------------


def test_the_table_lists_exactly_the_registered_games(table):
    assert sorted(table) == octax_core.list_games()
    for game_id, row in table.items():
        assert row.suite == suite_of(game_id)
        assert row.episodes_ended + row.episodes_cut == row.episodes


def test_references_are_sourced_and_beat_random(table):
    with_reference = [row for row in table.values() if row.has_reference]
    assert with_reference, "no game has a reference"
    for row in table.values():
        assert (row.reference_source is None) == (row.reference is None), row.game_id
        assert row.reference_detail, f"{row.game_id}: a reference, or its absence, is explained"
        if row.has_reference:
            assert row.reference_source in scores.REFERENCE_SOURCES, row.game_id
            assert row.reference > row.random_mean, row.game_id
            assert row.episodes_cut == 0, f"{row.game_id}: random play was cut, so no normalized score"
        if row.maximum is not None and row.has_reference:
            assert row.reference <= row.maximum, f"{row.game_id}: a reference above the rules' maximum"


def test_the_page_lists_every_row(table):
    page = (DOCS / "scores.md").read_text()
    listed = [line.split(" | ")[0].removeprefix("| ") for line in page.splitlines()
              if line.startswith("| ") and not line.startswith(("| game", "|---"))]
    assert listed == sorted(table), "docs/scores.md is stale: run python docs/scores.py --page-only"


@pytest.mark.parametrize("game_id", REMEASURED)
def test_random_scores_remeasure_exactly(script, game_id):
    """The script's own function, with the committed seed and episodes, gives the committed row."""
    saved = json.loads(resources.files("octax_gym").joinpath("data", "scores.json").read_text())
    committed = saved["games"][game_id]["random"]
    measured = script["random_score"](game_id, episodes=saved["episodes"], seed=saved["seed"],
                                      step_cap=script["RANDOM_STEP_CAP"].get(game_id))
    for field in ("mean", "std", "episodes", "ended", "cut", "step_cap", "mean_length"):
        assert measured[field] == committed[field], (game_id, field)
