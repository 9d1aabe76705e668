"""Boot a CHIP-8 ROM, run it for one second (60 frames) and print its screen; then run a batch of 4.

    python examples/boot_rom.py [ROM]     # default: our own Dodge (roms/dodge.ch8), its start screen
"""

import sys
from pathlib import Path

import jax
import numpy as np

import octax_core

DEFAULT_ROM = Path(__file__).resolve().parents[1] / "roms" / "dodge.ch8"

rom = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_ROM
machine = octax_core.Machine(quirks="chip8", instructions_per_frame=11)
run = jax.jit(machine.run_frames, static_argnums=2)  # frames is static: it sets the loop length

state = machine.boot(rom, jax.random.key(0))
state = run(state, 0, 60)  # 60 frames, no key held
print(octax_core.render_text(state))

# A batch is a vmap over the state (and the keys); the Machine config is shared.
keys = jax.random.split(jax.random.key(1), 4)
batch = jax.vmap(lambda k: machine.boot(rom, k))(keys)
batch = jax.jit(jax.vmap(lambda s: machine.run_frames(s, 0, 60)))(batch)
screens = octax_core.snapshot(batch)["screen"]  # (4, 32, 64) bool
print(f"batch of {screens.shape[0]}: screens {screens.shape}, lit pixels {screens.sum(axis=(1, 2)).tolist()}, "
      f"all equal to the single run: {bool(np.all(screens == octax_core.snapshot(state)['screen']))}")
