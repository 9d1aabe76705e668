"""A variant as a game: its source assembled into a ROM, and the GameSpec that plays it.

Every family keeps its score, lives and end in the same registers (`families.SCORE`, `LIVES`,
`GAME_OVER`), so every variant's spec gets the same score, lives and end functions
(`register_functions`): the variants differ only in their ROM (and name), which a mix holds as data.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
from typing import Mapping, Optional, Sequence

from octax_core.env.games.spec import GameSpec, register_value
from octax_core.generate.families import GAME_OVER, LIVES, SCORE, Family
from octax_core.generate.render import render
from octax_core.tools.octo import assemble

STARTUP = ((0, 10),)  # the play screen drawn, inside the 24-frame pause: each episode's first draws are its own
MAX_EPISODE_STEPS = 4500


def register_functions(score_register: int = SCORE, lives_register: Optional[int] = LIVES,
                       end: Sequence[int] = (GAME_OVER, 1)):
    """(score_fn, terminated_fn, lives_fn) reading V[score_register], V[lives_register] (None: no
    lives) and V[end[0]] == end[1]. Cached, so every game that keeps them in the same registers
    gets the very same functions: every family's variants, and an LLM's games that agree."""
    if len(end) != 2:
        raise ValueError(f"end must be [register, value], got {list(end)}")
    for name, register in (("score", score_register), ("lives", lives_register), ("end", end[0])):
        if register is not None and not 0 <= register <= 14:
            raise ValueError(f"the {name} register must be V0..VE (0..14; VF is the carry flag), got {register}")
    if not 0 <= end[1] <= 255:
        raise ValueError(f"the end value must be a byte 0..255, got {end[1]}")
    return _functions(int(score_register), None if lives_register is None else int(lives_register),
                      int(end[0]), int(end[1]))


@functools.lru_cache(maxsize=None)
def _functions(score_register: int, lives_register: Optional[int], end_register: int, end_value: int):

    def score_fn(state):
        return register_value(state, score_register)

    def terminated_fn(state):
        return state.V[end_register] == end_value

    lives_fn = None if lives_register is None else (lambda state: register_value(state, lives_register))
    return score_fn, terminated_fn, lives_fn


@dataclasses.dataclass(frozen=True)
class Variant:
    """One generated game: its name, family, parameters, Octo source and ROM."""

    name: str
    family: str
    params: Mapping
    source: str
    rom: bytes

    @property
    def sha1(self) -> str:
        return hashlib.sha1(self.rom).hexdigest()


def build_variant(family: Family, params: Mapping, name: str) -> Variant:
    """Renders and assembles one variant (a template that does not assemble raises AssemblyError)."""
    source = render(family, params)
    return Variant(name=name, family=family.name, params=dict(params), source=source, rom=assemble(source))


def variant_spec(name: str, rom_sha1: str, action_keys: Sequence[int] = (4, 6), description: str = "", *,
                 rom_file: Optional[str] = None, registers: Optional[Mapping] = None) -> GameSpec:
    """The GameSpec of a generated game whose ROM has `rom_sha1`.

    Args:
        rom_file: where the ROM store finds it: a file name in its folders, or an absolute path
            (`octax_gym.generated` gives the archive's own file); default `<name>.ch8`.
        registers: {"score": V index, "lives": V index or None, "end": [V index, value]}; None
            takes the families' (V5, V6, VE == 1) and their shared functions.
    """
    registers = dict(registers or {})
    score_fn, terminated_fn, lives_fn = register_functions(
        registers.get("score", SCORE), registers.get("lives", LIVES), tuple(registers.get("end", (GAME_OVER, 1))))
    return GameSpec(id=name, title=name, rom_file=rom_file or f"{name}.ch8", rom_sha1=rom_sha1,
                    action_keys=tuple(action_keys), score_fn=score_fn, terminated_fn=terminated_fn,
                    lives_fn=lives_fn, category="reaction", description=description or f"a generated game ({name})",
                    startup=STARTUP, quirks="chip8", max_episode_steps=MAX_EPISODE_STEPS)
