"""The emulator: CHIP-8, SUPER-CHIP and XO-CHIP machines as pure JAX functions of a state pytree.

Layered bottom-up: `rom` (program images), `platforms` (the three machines' shapes), `quirks`
(behaviour profiles), `state` (the state pytree, boot image, host views), `opcodes` and `decode`
(the opcode tables), `ops/` (one handler per opcode; `display` is the packed screen of every
platform), `gate` (work only some machines of a batch need), `cpu` (the one executor: fetch,
decode, execute, for all three platforms), `idle` (exact idle skipping's cycle detector),
`frame` (the one frame loop), `keypad` (key input), `machine` (`Machine`, the frozen config and
its entry points). Nothing here knows about games, envs or Gymnasium.
See docs/machine.md.
"""

from octax_core.emulator.decode import Kind
from octax_core.emulator.machine import Machine
from octax_core.emulator.platforms import PLATFORMS, Platform
from octax_core.emulator.quirks import QUIRK_PROFILES, Quirks, quirks_from_octo
from octax_core.emulator.rom import MAX_ROM_SIZE, PROGRAM_ADDRESS, Rom
from octax_core.emulator.state import FONT, FONT_ADDRESS, MachineState, poke, render_text, snapshot

__all__ = ["FONT", "FONT_ADDRESS", "Kind", "MAX_ROM_SIZE", "Machine", "MachineState", "PLATFORMS", "PROGRAM_ADDRESS",
           "Platform", "QUIRK_PROFILES", "Quirks", "Rom", "poke", "quirks_from_octo", "render_text", "snapshot"]
