"""Honest aggregate scores: normalized returns, the interquartile mean and bootstrap intervals.

A return means little across games until it is set between two fixed points: what uniform-random
play scores and what has been shown reachable (the reference). `normalized_score` computes
(score - random) / (reference - random) from the committed table (`score_table()`, made by
docs/scores.py, explained in docs/scores.md); a game with no reference that beats random has no
normalized score, and asking for one raises instead of inventing it.

Across runs and games, the statistics follow Agarwal et al. (2021), "Deep Reinforcement Learning
at the Edge of the Statistical Precipice" (NeurIPS), which the octax paper cites: the
interquartile mean (IQM) of all runs' scores pooled, and percentile confidence intervals from a
stratified bootstrap that resamples runs with replacement within each game. Scores come as a
(num_runs, num_games) matrix. The authors' package, rliable, does this, but its last release
(1.2.0, August 2024) fails to import beside pandas 3 and arch 7.2 ("TypeError: deprecate_kwarg()
missing 1 required positional argument"), so these few functions are written here on numpy,
following the paper's definitions. Each statistic is written once, over a stack of score matrices,
so that a bootstrap computes all its resamples in a few array operations instead of a Python call
each (a training run's learning curve asks for an interval per game at every evaluation; the times
are in docs/machine-log.md); a statistic of one matrix is the same code on a stack of none, so both
give the same bits.

    >>> from octax_gym import scores
    >>> matrix = np.stack([scores.normalized_score(g, raw[:, j]) for j, g in enumerate(games)], axis=1)
    >>> scores.stratified_bootstrap_ci(matrix, scores.iqm, reps=2000, seed=0)      # doctest: +SKIP
    Interval(point=0.41, low=0.33, high=0.50)
"""

from __future__ import annotations

import dataclasses
import functools
import json
from importlib import resources
from typing import Callable, Optional, Sequence

import numpy as np

from octax_gym.envs.choices import UnknownOptionError

REFERENCE_SOURCES = ("search", "scripted", "trained")  # where a reference may come from (docs/scores.md)
Statistic = Callable[[np.ndarray], float]


# --- statistics of a (num_runs, num_games) score matrix -------------------------------------------


def _matrix(scores) -> np.ndarray:
    """Scores as a float (num_runs, num_games) matrix; a 1-D array is one game's runs."""
    matrix = np.asarray(scores, np.float64)
    if matrix.ndim == 1:
        matrix = matrix[:, None]
    if matrix.ndim != 2 or matrix.size == 0:
        raise ValueError(f"scores must be a non-empty (num_runs, num_games) matrix, got shape {matrix.shape}")
    return matrix


def _iqm(matrices: np.ndarray) -> np.ndarray:
    """(..., runs, games) -> (...): each matrix's scores flattened, the int(n / 4) lowest and the
    int(n / 4) highest left out, the rest averaged (`scipy.stats.trim_mean(m, 0.25, axis=None)`'s
    partition and mean, the same bits); a matrix with a NaN is NaN, as there, even where the NaN
    would be trimmed."""
    flat = matrices.reshape(*matrices.shape[:-2], -1)
    n = flat.shape[-1]
    low, high = int(0.25 * n), n - int(0.25 * n)
    middle = np.mean(np.partition(flat, (low, high - 1), axis=-1)[..., low:high], axis=-1)
    return np.where(np.isnan(flat).any(axis=-1), np.nan, middle)


def _mean(matrices: np.ndarray) -> np.ndarray:
    return np.mean(np.mean(matrices, axis=-2), axis=-1)


def _median(matrices: np.ndarray) -> np.ndarray:
    return np.median(np.mean(matrices, axis=-2), axis=-1)


def _optimality_gap(matrices: np.ndarray, gamma: float = 1.0) -> np.ndarray:
    below = np.minimum(matrices, gamma)
    return gamma - np.mean(below.reshape(*below.shape[:-2], -1), axis=-1)


def iqm(scores) -> float:
    """The interquartile mean: the mean of the middle 50% of all runs' scores, games pooled.

    As in the paper (and rliable), `scipy.stats.trim_mean(scores, 0.25)` over the flattened
    scores: of n scores, the int(n / 4) lowest and the int(n / 4) highest are left out.
    """
    return float(_iqm(_matrix(scores)))


def mean(scores) -> float:
    """The mean over games of each game's mean score (rliable's aggregate mean)."""
    return float(_mean(_matrix(scores)))


def median(scores) -> float:
    """The median over games of each game's mean score (rliable's aggregate median)."""
    return float(_median(_matrix(scores)))


def optimality_gap(scores, gamma: float = 1.0) -> float:
    """How far the scores fall short of `gamma` on average, scores above it counting as gamma.

    On normalized scores with gamma = 1: the mean shortfall from the reference, so lower is better.
    """
    return float(_optimality_gap(_matrix(scores), gamma))


STATISTICS: dict[str, Statistic] = {"iqm": iqm, "mean": mean, "median": median, "optimality_gap": optimality_gap}
# Each statistic above over a stack of matrices, for the bootstrap; any other callable is called
# once per resample.
_STACKED = ((iqm, _iqm), (mean, _mean), (median, _median), (optimality_gap, _optimality_gap))


@dataclasses.dataclass(frozen=True)
class Interval:
    """A statistic of the scores and its bootstrap confidence interval."""

    point: float
    low: float
    high: float


def bootstrap_distribution(scores, statistic: Statistic = iqm, reps: int = 2000, seed: int = 0) -> np.ndarray:
    """The statistic of `reps` stratified resamples of the score matrix, shape (reps,).

    Each game (column) is a stratum: a resample draws num_runs of its runs with replacement,
    every game alike, so each keeps its weight. The draws are, exactly,
    `rows = np.random.default_rng(seed).integers(0, num_runs, (reps, num_runs, num_games))`, and
    resample r holds `scores[rows[r, i, j], j]` as run i of game j.
    """
    matrix = _matrix(scores)
    if reps < 1:
        raise ValueError(f"reps must be at least 1, got {reps}")
    num_runs, num_games = matrix.shape
    rows = np.random.default_rng(seed).integers(0, num_runs, (reps, num_runs, num_games))
    resamples = matrix[rows, np.arange(num_games)]  # (reps, num_runs, num_games)
    stacked = next((of_stack for scalar, of_stack in _STACKED if scalar is statistic), None)
    if stacked is not None:
        return np.asarray(stacked(resamples), np.float64)
    return np.array([statistic(resample) for resample in resamples], np.float64)


def stratified_bootstrap_ci(scores, statistic: Statistic = iqm, reps: int = 2000, confidence: float = 0.95,
                            seed: int = 0) -> Interval:
    """The statistic of the scores, and its percentile interval over a stratified bootstrap.

    The interval runs from the (1 - confidence) / 2 to the (1 + confidence) / 2 quantile of
    `bootstrap_distribution(scores, statistic, reps, seed)` (numpy's linear interpolation), as
    rliable's percentile intervals do.
    """
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must lie strictly between 0 and 1, got {confidence}")
    distribution = bootstrap_distribution(scores, statistic, reps, seed)
    low, high = np.percentile(distribution, [50 * (1 - confidence), 50 * (1 + confidence)])
    return Interval(point=statistic(_matrix(scores)), low=float(low), high=float(high))


def aggregate(scores, reps: int = 2000, confidence: float = 0.95, seed: int = 0) -> dict[str, Interval]:
    """IQM, mean, median and optimality gap, each with its interval (the paper's four)."""
    return {name: stratified_bootstrap_ci(scores, statistic, reps, confidence, seed)
            for name, statistic in STATISTICS.items()}


# --- the committed per-game table -----------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class GameScores:
    """One game's row of the table (docs/scores.md says how each value was measured)."""

    game_id: str
    suite: str
    random_mean: float  # mean return of uniform-random play
    random_std: float
    episodes: int  # random episodes played
    episodes_ended: int  # of them, those that ended (terminated, or truncated at max_episode_steps)
    episodes_cut: int  # of them, those cut shorter by the measurement's step cap (slow games)
    reference: Optional[float]  # None: no normalized score
    reference_source: Optional[str]  # one of REFERENCE_SOURCES, or None
    reference_detail: str  # how the reference was found, or why there is none
    maximum: Optional[float]  # the highest return the rules allow, where known

    @property
    def has_reference(self) -> bool:
        return self.reference is not None


@functools.lru_cache(maxsize=None)
def score_table() -> dict[str, GameScores]:
    """Every registered game's committed random and reference scores, by game id."""
    table = json.loads(resources.files("octax_gym").joinpath("data", "scores.json").read_text())
    return {game_id: GameScores(
        game_id=game_id, suite=row["suite"], random_mean=row["random"]["mean"], random_std=row["random"]["std"],
        episodes=row["random"]["episodes"], episodes_ended=row["random"]["ended"],
        episodes_cut=row["random"]["cut"], reference=row["reference"], reference_source=row["reference_source"],
        reference_detail=row["reference_detail"], maximum=row["maximum"],
    ) for game_id, row in table["games"].items()}


def normalized_score(game_id: str, score):
    """(score - random) / (reference - random) for the game: 0 is random play, 1 the reference.

    `score` may be a number or an array of them (a float or a float array comes back).

    Raises:
        UnknownOptionError: a game the table does not list (a KeyError and a ValueError).
        ValueError: a game with no reference (its `reference_detail` says why).
    """
    table = score_table()
    if game_id not in table:
        raise UnknownOptionError("scored game", game_id, sorted(table))
    row = table[game_id]
    if row.reference is None:
        raise ValueError(f"{game_id} has no normalized score: {row.reference_detail}")
    normalized = (np.asarray(score, np.float64) - row.random_mean) / (row.reference - row.random_mean)
    return float(normalized) if normalized.ndim == 0 else normalized


def normalized_matrix(game_ids: Sequence[str], scores) -> np.ndarray:
    """A (num_runs, num_games) matrix of returns, column j of game `game_ids[j]`, normalized."""
    matrix = _matrix(scores)
    if matrix.shape[1] != len(game_ids):
        raise ValueError(f"{len(game_ids)} game ids for {matrix.shape[1]} columns of scores")
    return np.stack([normalized_score(game_id, matrix[:, j]) for j, game_id in enumerate(game_ids)], axis=1)
