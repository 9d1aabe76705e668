"""A variant as a game: its source assembled into a ROM, and the GameSpec that plays it.

Every family keeps its score, lives and end in the same registers (`families.SCORE`, `LIVES`,
`GAME_OVER`), so the score, lives and end functions here are module-level functions shared by
every variant's spec: the variants differ only in their ROM (and name), which a mix holds as data.
"""

from __future__ import annotations

import dataclasses
import hashlib
from typing import Mapping

from octax_core.env.games.spec import GameSpec, register_value
from octax_core.generate.families import GAME_OVER, LIVES, SCORE, Family
from octax_core.generate.render import render
from octax_core.tools.octo import assemble

STARTUP = ((0, 10),)  # the play screen drawn, inside the 24-frame pause: each episode's first draws are its own
MAX_EPISODE_STEPS = 4500


def score(state):
    """V5, every family's score."""
    return register_value(state, SCORE)


def lives(state):
    """V6, every family's lives."""
    return register_value(state, LIVES)


def game_over(state):
    """VE == 1, every family's end."""
    return state.V[GAME_OVER] == 1


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


def variant_spec(name: str, rom_sha1: str, action_keys=(4, 6), description: str = "", *,
                 score_fn=score, terminated_fn=game_over, lives_fn=lives) -> GameSpec:
    """The GameSpec of a generated game whose ROM is `<name>.ch8` with `rom_sha1`.

    The score, lives and end are the families' shared functions unless given (an LLM's game
    keeps them where its author said, or where the tracer found them).
    """
    return GameSpec(id=name, title=name, rom_file=f"{name}.ch8", rom_sha1=rom_sha1, action_keys=tuple(action_keys),
                    score_fn=score_fn, terminated_fn=terminated_fn, lives_fn=lives_fn, category="reaction",
                    description=description or f"a generated game ({name})", startup=STARTUP,
                    quirks="chip8", max_episode_steps=MAX_EPISODE_STEPS)
