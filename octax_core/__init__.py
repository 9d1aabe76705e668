"""octax_core: a jitted, batched CHIP-8 machine in JAX (pure JAX + numpy), the game registry and
a functional, Gymnax-style env API over it, and the Octo assembler and disassembler
(`assemble`, `disassemble`).

See docs/machine.md for the machine contract and docs/env.md for the env API.
"""

from octax_core.decode import Kind
from octax_core.env import Env, EnvConfig, EnvParams, EnvState, make, make_config, make_params
from octax_core.games import GameSpec, get_spec, list_games
from octax_core.machine import Machine
from octax_core.octo import AssemblyError, assemble
from octax_core.quirks import QUIRK_PROFILES, Quirks
from octax_core.rom import MAX_ROM_SIZE, PROGRAM_ADDRESS, Rom
from octax_core.state import FONT, FONT_ADDRESS, MachineState, poke, render_text, snapshot

__all__ = [
    "AssemblyError", "FONT", "FONT_ADDRESS", "Env", "EnvConfig", "EnvParams", "EnvState", "GameSpec", "Kind",
    "MAX_ROM_SIZE", "Machine", "MachineState", "PROGRAM_ADDRESS", "QUIRK_PROFILES", "Quirks", "Rom",
    "assemble", "disassemble", "get_spec", "list_games", "make", "make_config", "make_params", "poke", "render_text", "snapshot",
]


def __getattr__(name):
    # The disassembler loads on first use (`octax_core.disassemble`), like optional extras do.
    if name == "disassemble":
        from octax_core.octo.disassembler import disassemble
        return disassemble
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
