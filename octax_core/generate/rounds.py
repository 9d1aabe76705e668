"""A round: candidates built, checked in one batch (`filters.check`), and turned into archive rows.

A candidate is a program with a name and where its score and end are; a family's come from
its template (`family_candidates`), an LLM's from `octax_core.generate.llm`. Both go through
`judge`, so a family variant and an LLM's game are held to the same checks.
"""

from __future__ import annotations

import dataclasses
import hashlib
from typing import Mapping, Optional, Sequence

from octax_core.generate import filters
from octax_core.generate.build import build_variant, variant_spec
from octax_core.generate.families import GAME_OVER, LIVES, SCORE, Family
from octax_core.generate.sample import sample_params

FAMILY_REGISTERS = {"score": SCORE, "lives": LIVES, "end": [GAME_OVER, 1]}


@dataclasses.dataclass(frozen=True)
class Candidate:
    """A program to judge. `rom` is None where the source did not assemble (`error` says why)."""

    name: str
    family: str
    params: Mapping
    source: str
    rom: Optional[bytes]
    split: str = "train"
    action_keys: tuple[int, ...] = (4, 6)
    registers: Mapping = dataclasses.field(default_factory=lambda: dict(FAMILY_REGISTERS))
    error: str = ""
    extra: Mapping = dataclasses.field(default_factory=dict)  # more fields for its archive row

    @property
    def sha1(self) -> Optional[str]:
        return None if self.rom is None else hashlib.sha1(self.rom).hexdigest()


def family_candidates(family: Family, count: int, seed: int) -> list[Candidate]:
    """Variants 0..count-1 of `family` under `seed`, named `<family>-<seed>-<index>`."""
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count}")
    candidates = []
    for index in range(count):
        params = sample_params(family, seed, index)
        variant = build_variant(family, params, f"{family.name}-s{seed}-{index:04d}")
        candidates.append(Candidate(variant.name, family.name, variant.params, variant.source, variant.rom,
                                    split=family.split_of(params), action_keys=family.action_keys))
    return candidates


def judge(candidates: Sequence[Candidate], settings: filters.Settings = filters.Settings()) -> list[dict]:
    """Every candidate's archive row; those that assemble and are not a repeat run in one batch."""
    seen: dict[str, str] = {}
    runnable = []
    for candidate in candidates:
        if candidate.rom is not None and candidate.sha1 not in seen:
            seen[candidate.sha1] = candidate.name
            runnable.append(candidate)
    verdicts = {}
    if runnable:
        specs = [variant_spec(c.name, c.sha1, c.action_keys, registers=c.registers) for c in runnable]
        verdicts = dict(zip((c.name for c in runnable), filters.check(specs, [c.rom for c in runnable], settings)))
    rows = []
    for candidate in candidates:
        verdict = verdicts.get(candidate.name)
        if candidate.rom is None:
            reasons = [f"does not assemble: {candidate.error}"]
        elif verdict is None:
            reasons = [f"the same program as {seen[candidate.sha1]}"]
        else:
            reasons = list(verdict.reasons)
        rows.append({
            "name": candidate.name, "family": candidate.family, "params": dict(candidate.params),
            "sha1": candidate.sha1, "accepted": not reasons, "reasons": reasons,
            "random_score": None if verdict is None else verdict.random_score,
            "reference_score": None if verdict is None else verdict.reference_score,
            "random_horizon_score": None if verdict is None else verdict.random_horizon,
            "split": candidate.split, "source": f"{candidate.name}.8o",
            "rom": None if candidate.rom is None else f"{candidate.name}.ch8",
            "action_keys": list(candidate.action_keys), "registers": dict(candidate.registers), **candidate.extra})
    return rows


def settings_row(settings: filters.Settings) -> dict:
    """The settings as the archive records them, with the acceptance thresholds."""
    return {**dataclasses.asdict(settings), "margin": filters.MARGIN, "ratio": filters.RATIO,
            "ended_share": filters.ENDED_SHARE}
