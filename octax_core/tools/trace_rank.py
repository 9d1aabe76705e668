"""Which register is the score, the lives, the game-over flag? A ranking from a `Trace` and the ROM.

The paper (appendix, Score Detection Methodology) finds its reward registers in two ways:
static analysis of the ROM (an FX33 BCD instruction suggests a number shown on screen) and
dynamic monitoring (a register that rises during play is likely a score, one that falls a lives
count). This module does both, for every register and three roles, each scored in [0, 1]:

- score: rises, rarely, during play (`_rise`); the ROM shows it with FX33 (`RomFacts.bcd`);
  and, when the trace has a reward, it moves with the reward (`_reward_corr`). A counter that
  rises on every step (a clock, a distance) scores low, so a score that *is* a clock is missed.
- lives: falls, by 1, rarely, from a small peak (`_fall`); has fallen by the end of each
  episode that ended; the ROM decrements it (7XFF) and tests it for 0 (3X00/4X00).
- game_over: one value (or leaving one value) marks the steps where episodes ended
  (`_end_flag`, a Matthews correlation). Without any ended episode there is no evidence at all.

The weights are hand-set, not fitted; docs/trace.md gives the suite's hit rate and its misses.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from octax_core.tools.rom_scan import RomFacts, rom_facts
from octax_core.tools.trace import Trace

ROLES = ("score", "lives", "game_over")
NUM_REGISTERS = 16
_RARE_RATE = 0.1  # change rate (per step) at which an event register scores half for rarity


@dataclasses.dataclass(frozen=True)
class Candidate:
    """One register's claim to one role."""

    register: int  # 0..15, V0..VF
    confidence: float  # 0..1, comparable within one role and one trace only
    reason: str  # the evidence, in a few words

    @property
    def name(self) -> str:
        return f"V{self.register:X}"


@dataclasses.dataclass(frozen=True)
class Ranking:
    """All 16 registers per role, best first (ties: lower register first), plus caveats."""

    score: tuple[Candidate, ...]
    lives: tuple[Candidate, ...]
    game_over: tuple[Candidate, ...]
    notes: tuple[str, ...]  # what the trace could not tell (no reward, no episode ended, ...)

    def top(self, role: str, k: int = 3) -> tuple[Candidate, ...]:
        """The best `k` candidates for `role` (one of `ROLES`)."""
        if role not in ROLES:
            raise ValueError(f"unknown role {role!r}; valid: {', '.join(ROLES)}")
        return getattr(self, role)[:k]


def rank_registers(trace: Trace) -> Ranking:
    """Ranks V0..VF as score, lives and game-over candidates (see the module docstring)."""
    facts = rom_facts(trace.rom)
    over = ended_rows(trace)
    # An episode's first step is the program setting up its registers, not play: it is left out.
    play = ~trace.episode_start.reshape(-1)
    deltas = trace.deltas.reshape(-1, NUM_REGISTERS).astype(np.int32)
    notes = []
    if not trace.has_reward or not trace.reward.any():
        notes.append("no reward in the trace: score ranked from register trends and the ROM alone")
    if not over.any():
        notes.append("no episode ended in the trace: game-over candidates have no evidence "
                     "(play longer, or use a spec with a termination)")
    # A score rises during play; a flag that rises as the game ends is the game-over role's.
    during_play = play & ~over.reshape(-1)
    roles = {"score": _score(trace, deltas[during_play], trace.reward.reshape(-1)[during_play], facts),
             "lives": _lives(trace, deltas[play], facts),
             "game_over": _game_over(trace, over)}
    return Ranking(**{role: _sorted(*scored) for role, scored in roles.items()}, notes=tuple(notes))


def _sorted(confidence: np.ndarray, reasons: list[str]) -> tuple[Candidate, ...]:
    order = sorted(range(NUM_REGISTERS), key=lambda k: (-round(float(confidence[k]), 6), k))
    return tuple(Candidate(k, float(confidence[k]), reasons[k]) for k in order)


# --- roles --------------------------------------------------------------------------------------


def _score(trace: Trace, deltas: np.ndarray, reward: np.ndarray, facts: RomFacts):
    rise, rise_why = _rise(deltas)
    parts = [(rise, rise_why), (facts.bcd.astype(float), _flag_reasons(facts.bcd, "shown by FX33"))]
    if trace.has_reward and reward.any():
        corr, corr_why = _reward_corr(deltas, reward)
        return _blend(parts + [(corr, corr_why)], (0.25, 0.15, 0.6))
    return _blend(parts, (0.65, 0.35))


def _lives(trace: Trace, deltas: np.ndarray, facts: RomFacts):
    start = start_values(trace)
    fall, fall_why = _fall(deltas, episode_peaks(trace))
    shown = facts.bcd | facts.digit
    static = 0.4 * facts.decremented + 0.4 * facts.tested_zero + 0.2 * shown
    static_why = [_static_lives_reason(facts.decremented[k], facts.tested_zero[k], shown[k])
                  for k in range(NUM_REGISTERS)]
    parts = [(fall, fall_why), (static, static_why)]
    fell, fell_why = _fell_by_end(trace, start)
    if fell is None:
        return _blend(parts, (0.6, 0.4))
    return _blend(parts + [(fell, fell_why)], (0.45, 0.3, 0.25))


def _game_over(trace: Trace, over: np.ndarray):
    if not over.any():
        return np.zeros(NUM_REGISTERS), ["no episode ended"] * NUM_REGISTERS
    flag, why = _end_flag(trace.regs.reshape(-1, NUM_REGISTERS), over.reshape(-1), int(trace.terminated.sum()))
    # A flag is written when the game ends, rarely; a loop counter that happens to hold some value
    # when the game stops changes on most steps.
    _, _, _, rate = _change_counts(trace.deltas.reshape(-1, NUM_REGISTERS))
    return flag / (1.0 + rate / 0.3), why


def _blend(parts, weights):
    """Weighted sum of the feature scores; the reason lists the features that contributed."""
    confidence = sum(w * score for (score, _), w in zip(parts, weights))
    reasons = []
    for k in range(NUM_REGISTERS):
        weighted = [(w * score[k], why[k]) for (score, why), w in zip(parts, weights) if why[k]]
        strong = [why for value, why in weighted if value >= 0.05]
        weak = max(weighted, default=(0.0, ""))
        reasons.append("; ".join(strong) or (f"weak: {weak[1]}" if weak[0] > 0 else "no evidence"))
    return np.clip(confidence, 0.0, 1.0), reasons


# --- dynamic features ---------------------------------------------------------------------------


def _change_counts(deltas: np.ndarray):
    changes = (deltas != 0).sum(0)
    return changes, (deltas > 0).sum(0), (deltas < 0).sum(0), changes / max(len(deltas), 1)


def _rarity(rate: np.ndarray) -> np.ndarray:
    """1 for a register that changes on few steps, 0.5 at `_RARE_RATE`, towards 0 for a clock."""
    return 1.0 / (1.0 + rate / _RARE_RATE)


def _rise(deltas: np.ndarray):
    """Score-like: the changes are rises, on few steps, and there are at least 3 of them."""
    changes, ups, _, rate = _change_counts(deltas)
    up_frac = ups / np.maximum(changes, 1)
    score = up_frac * _rarity(rate) * np.minimum(ups / 3, 1.0)
    why = [f"rises on {ups[k]}/{changes[k]} changes ({100 * rate[k]:.1f}% of steps)" if ups[k] else ""
           for k in range(NUM_REGISTERS)]
    return score, why


def _fall(deltas: np.ndarray, peak: np.ndarray):
    """Lives-like: the changes are falls, mostly by 1, on few steps, from a small peak value."""
    changes, _, downs, rate = _change_counts(deltas)
    by_one = (deltas == -1).sum(0)
    small_peak = np.where((peak >= 1) & (peak <= 99), 1.0, 0.2)
    score = (downs / np.maximum(changes, 1)) * (0.5 + 0.5 * by_one / np.maximum(downs, 1)) \
        * _rarity(rate) * np.minimum(downs / 2, 1.0) * small_peak
    why = [f"falls on {downs[k]}/{changes[k]} changes ({by_one[k]} by 1) from {peak[k]}" if downs[k] else ""
           for k in range(NUM_REGISTERS)]
    return score, why


def _reward_corr(deltas: np.ndarray, reward: np.ndarray):
    """|correlation| of each register's change with the reward, step by step."""
    d = deltas - deltas.mean(0)
    r = reward - reward.mean()
    denom = np.sqrt((d * d).sum(0) * (r * r).sum())
    corr = np.where(denom > 0, (d * r[:, None]).sum(0) / np.where(denom > 0, denom, 1), 0.0)
    why = [f"{'moves with' if c > 0 else 'moves against'} the reward (r={c:+.2f})" for c in corr]
    return np.abs(corr), why


def _fell_by_end(trace: Trace, start: np.ndarray):
    """Fraction of terminated episodes whose last row is below the start value; None if none ended."""
    ends = trace.terminated
    if not ends.any():
        return None, None
    last = trace.regs[ends].astype(int)  # (episodes, 16)
    fell = (last < start).mean(0)
    return fell, [f"below its start at {100 * f:.0f}% of game ends" if f else "" for f in fell]


def start_values(trace: Trace) -> np.ndarray:
    """(16,) int: each register's most common value after an episode's first step.

    Not `reset_regs`: a raw ROM starts from power-on, all zeros, and sets its lives count in its
    first instructions; a registered game's start-up has already run them, and both agree.
    """
    first = trace.regs[trace.episode_start].astype(int)  # (episodes, 16)
    return np.array([np.bincount(first[:, k], minlength=256).argmax() for k in range(NUM_REGISTERS)])


def episode_peaks(trace: Trace) -> np.ndarray:
    """(16,) int: each register's most common episode maximum, the value a count falls from.

    A raw ROM may set its lives count after the first step (behind a title screen), where
    `start_values` would still read 0; the maximum sees it.
    """
    n_envs = trace.regs.shape[1]
    episode = (np.cumsum(trace.episode_start, axis=0) - 1) * n_envs + np.arange(n_envs)  # (T, N) ids
    peaks = np.zeros((int(episode.max()) + 1, NUM_REGISTERS), int)
    np.maximum.at(peaks, episode.reshape(-1), trace.regs.reshape(-1, NUM_REGISTERS).astype(int))
    return np.array([np.bincount(peaks[:, k], minlength=256).argmax() for k in range(NUM_REGISTERS)])


def ended_rows(trace: Trace) -> np.ndarray:
    """(T, N) bool: the rows that show a game over.

    With the spec's termination, the terminal rows. With stalls, each stall's whole window: the
    game was over on every one of its `stall_steps` still steps, not only on the last.
    """
    over = trace.terminated.copy()
    for back in range(1, min(trace.stall_steps, len(over))):
        over[:-back] |= trace.terminated[back:]
    return over


def _end_flag(regs: np.ndarray, over: np.ndarray, n_ends: int):
    """Best test `V == v` or `V != v` as a detector of the ended rows, per register, scored by its
    Matthews correlation with them (0 for a test that is always or never true).

    `v` is tried among the values seen at ended rows (for ==) and the register's most common value
    elsewhere (for !=). Not F1: where episodes are very short (Cavern4 under random play ends
    half its steps), a constant register's `V == c` has an F1 of 0.65 while telling nothing.
    The score is scaled down when fewer than 3 episodes ended.
    """
    support = min(n_ends / 3, 1.0)
    scores, why = np.zeros(NUM_REGISTERS), [""] * NUM_REGISTERS
    for k in range(NUM_REGISTERS):
        values = regs[:, k]
        tests = [("==", v, values == v) for v in np.unique(values[over])]
        common = np.bincount(values[~over], minlength=256).argmax() if (~over).any() else values[0]
        tests.append(("!=", common, values != common))
        for op, v, hit in tests:
            score = max(_matthews(hit, over), 0.0) * support
            if score > scores[k]:
                scores[k] = score
                why[k] = (f"V{k:X} {op} {int(v)} at {100 * np.count_nonzero(hit & over) / np.count_nonzero(over):.0f}%"
                          f" of ended steps, {100 * np.count_nonzero(hit & ~over) / max(np.count_nonzero(~over), 1):.1f}%"
                          " of others")
    return scores, [w or "no evidence" for w in why]


def _matthews(predicted: np.ndarray, actual: np.ndarray) -> float:
    """Matthews correlation of two boolean arrays (the phi coefficient); 0 when either is constant."""
    tp = np.count_nonzero(predicted & actual)
    fp = np.count_nonzero(predicted & ~actual)
    fn = np.count_nonzero(~predicted & actual)
    tn = predicted.size - tp - fp - fn
    denom = float(tp + fp) * (tp + fn) * (tn + fp) * (tn + fn)
    return (tp * tn - fp * fn) / np.sqrt(denom) if denom > 0 else 0.0


# --- reasons --------------------------------------------------------------------------------------


def _static_lives_reason(decremented: bool, tested_zero: bool, shown: bool) -> str:
    uses = [text for flag, text in ((decremented, "ADD -1"), (tested_zero, "tested for 0"), (shown, "shown"))
            if flag]
    return "ROM: " + ", ".join(uses) if uses else ""


def _flag_reasons(flags: np.ndarray, text: str) -> list[str]:
    return [text if flag else "" for flag in flags]
