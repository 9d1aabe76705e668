"""The emulator: a CHIP-8 machine as pure JAX functions of a state pytree.

Layered bottom-up: `rom` (program images), `quirks` (behaviour profiles), `state` (the state
pytree, boot image, host views), `decode` (opcode table), `ops/` (one handler per opcode),
`cpu` (fetch, decode, execute, the frame), `keypad` (key input), `machine` (`Machine`, the
frozen config and its entry points). Nothing here knows about games, envs or Gymnasium.
See docs/machine.md.
"""

from octax_core.emulator.decode import Kind
from octax_core.emulator.machine import Machine
from octax_core.emulator.quirks import QUIRK_PROFILES, Quirks
from octax_core.emulator.rom import MAX_ROM_SIZE, PROGRAM_ADDRESS, Rom
from octax_core.emulator.state import FONT, FONT_ADDRESS, MachineState, poke, render_text, snapshot

__all__ = ["FONT", "FONT_ADDRESS", "Kind", "MAX_ROM_SIZE", "Machine", "MachineState", "PROGRAM_ADDRESS",
           "QUIRK_PROFILES", "Quirks", "Rom", "poke", "render_text", "snapshot"]
