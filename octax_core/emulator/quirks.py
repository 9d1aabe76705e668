"""Quirk profiles: the behaviours on which CHIP-8 interpreters disagree.

Field names follow the Timendus quirks test ROM (`5-quirks`), so that its screen reports each
field by name. Quirks change the traced program, so they live in the frozen `Machine` config,
never in the state.

A machine that runs several games at once (a mix, `Machine(profiles=...)`) gives each machine of
the batch its own profile. Its quirks are then a `Quirks` whose fields are the profiles' common
answer (a Python bool, as for one profile) where they agree, and the machine's own answer (a bool
array, looked up from its profile index) where they differ; `choose` is how a handler reads a
field either way, so a fixed profile traces exactly the program it always did.
"""

from __future__ import annotations

import dataclasses
from typing import Sequence, Union

import jax.numpy as jnp
import numpy as np


@dataclasses.dataclass(frozen=True)
class Quirks:
    """One interpreter's answers to the CHIP-8 ambiguities.

    Attributes:
        vf_reset: 8XY1/8XY2/8XY3 set VF to 0 (COSMAC VIP).
        memory_increment: FX55/FX65 leave I advanced by X + 1.
        display_wait: a DXYN waits for the display refresh, so it ends its frame.
        clipping: sprites are cut at the right and bottom edges instead of wrapping.
        shift_uses_vy: 8XY6/8XYE shift VY into VX; otherwise VX is shifted in place.
        jump_uses_vx: BNNN jumps to NNN + VX (X = high nibble of NNN); otherwise NNN + V0.
    """

    vf_reset: bool
    memory_increment: bool
    display_wait: bool
    clipping: bool
    shift_uses_vy: bool
    jump_uses_vx: bool


FIELDS = tuple(field.name for field in dataclasses.fields(Quirks))


def choose(flag, if_true, if_false):
    """A quirk's two behaviours: picked while tracing for a fixed answer (a Python bool), per
    machine for an answer that is data (a bool array, in a mix of profiles)."""
    if isinstance(flag, (bool, np.bool_)):
        return if_true if flag else if_false
    return jnp.where(flag, if_true, if_false)


def common(profiles: Sequence[Quirks]) -> dict[str, bool]:
    """The fields on which every profile agrees, with their answer."""
    return {name: getattr(profiles[0], name) for name in FIELDS
            if len({getattr(profile, name) for profile in profiles}) == 1}


def lane_quirks(profiles: Sequence[Quirks], index) -> Quirks:
    """The quirks of the machine running profile `index` (an int32 scalar, traced): the common
    answers as Python bools, the others as bool scalars looked up in a table of the profiles."""
    shared = common(profiles)
    return Quirks(**{name: shared[name] if name in shared
                     else jnp.asarray([getattr(profile, name) for profile in profiles])[index] for name in FIELDS})


QUIRK_PROFILES: dict[str, Quirks] = {
    # COSMAC VIP, the original interpreter most classic games were written for.
    "chip8": Quirks(
        vf_reset=True,
        memory_increment=True,
        display_wait=True,
        clipping=True,
        shift_uses_vy=True,
        jump_uses_vx=False,
    ),
    # SUPER-CHIP as modern interpreters (Octo's "schip" setting) run it.
    "schip": Quirks(
        vf_reset=False,
        memory_increment=False,
        display_wait=False,
        clipping=True,
        shift_uses_vy=False,
        jump_uses_vx=True,
    ),
    # XO-CHIP as Octo runs it: FX55/FX65 advance I, sprites wrap at the edges, shifts read VY.
    "xochip": Quirks(
        vf_reset=False,
        memory_increment=True,
        display_wait=False,
        clipping=False,
        shift_uses_vy=True,
        jump_uses_vx=False,
    ),
}


OCTO_QUIRK_OPTIONS = ("shiftQuirks", "loadStoreQuirks", "vfOrderQuirks", "clipQuirks", "jumpQuirks",
                      "vBlankQuirks", "logicQuirks")


def quirks_from_octo(options: dict) -> Quirks:
    """The `Quirks` that Octo's option flags describe (the Chip8 Community Archive's programs.json
    gives each program its own). A flag left out is false, as in Octo; other keys (colours,
    tickrate, ...) are ignored.

    Raises:
        ValueError: vfOrderQuirks is set (flags written before the result; not modelled) or a
            flag is not true, false, 1 or 0.
    """
    flags = {}
    for name in OCTO_QUIRK_OPTIONS:
        value = options.get(name, False)
        if value not in (False, True):  # the archive writes both true/false and 1/0
            raise ValueError(f"Octo option {name} must be true, false, 1 or 0, got {value!r}")
        flags[name] = bool(value)
    if flags["vfOrderQuirks"]:
        raise ValueError("Octo's vfOrderQuirks (VF written before the result) is not modelled; "
                         "every instruction here writes its flag after its result")
    return Quirks(vf_reset=flags["logicQuirks"], memory_increment=not flags["loadStoreQuirks"],
                  display_wait=flags["vBlankQuirks"], clipping=flags["clipQuirks"],
                  shift_uses_vy=not flags["shiftQuirks"], jump_uses_vx=flags["jumpQuirks"])


def resolve_quirks(quirks: Union[str, Quirks]) -> Quirks:
    """Returns the `Quirks` for a profile name, or `quirks` itself.

    Raises:
        ValueError: an unknown profile name; the message lists the valid ones.
        TypeError: neither a name nor a `Quirks`.
    """
    if isinstance(quirks, Quirks):
        return quirks
    if isinstance(quirks, str):
        if quirks not in QUIRK_PROFILES:
            valid = ", ".join(repr(name) for name in QUIRK_PROFILES)
            raise ValueError(f"unknown quirk profile {quirks!r}; valid profiles: {valid}")
        return QUIRK_PROFILES[quirks]
    raise TypeError(f"quirks must be a profile name or a Quirks, got {type(quirks).__name__}")
