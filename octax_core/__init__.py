"""octax_core: a jitted, batched CHIP-8 machine in JAX (pure JAX + numpy).

See docs/machine.md for the exact machine contract.
"""

from octax_core.decode import Kind
from octax_core.machine import Machine
from octax_core.quirks import QUIRK_PROFILES, Quirks
from octax_core.rom import MAX_ROM_SIZE, PROGRAM_ADDRESS, Rom
from octax_core.state import FONT, FONT_ADDRESS, MachineState, poke, render_text, snapshot

__all__ = [
    "FONT", "FONT_ADDRESS", "Kind", "MAX_ROM_SIZE", "Machine", "MachineState", "PROGRAM_ADDRESS",
    "QUIRK_PROFILES", "Quirks", "Rom", "poke", "render_text", "snapshot",
]
