"""`python -m octax_core.demo [ROM]`: boot a ROM, run it a second, print the screen.

The default is the CHIP-8 test suite's IBM logo from ../shared. It also runs a vmapped batch to
show the batched path, and prints how fast that went.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import jax

import octax_core

DEFAULT_ROM = Path(__file__).resolve().parents[2] / "shared" / "roms" / "test-suite" / "2-ibm-logo.ch8"


def main(argv: list[str]) -> int:
    rom = octax_core.Rom.load(argv[0] if argv else DEFAULT_ROM)
    machine = octax_core.Machine(quirks="chip8", instructions_per_frame=11)
    print(f"{rom.name}: {len(rom.data)} bytes, sha1 {rom.sha1}")

    run = jax.jit(machine.run_frames, static_argnums=2)
    state = run(machine.boot(rom, jax.random.key(0)), 0, 60)
    print(octax_core.render_text(state, on="\u2588", off=" "))

    num_machines, frames = 256, 240
    keys = jax.random.split(jax.random.key(1), num_machines)
    batch = jax.vmap(lambda k: machine.boot(rom, k))(keys)
    run_batch = jax.jit(jax.vmap(lambda s: machine.run_frames(s, 0, frames)))
    jax.block_until_ready(run_batch(batch))  # compile
    start = time.perf_counter()
    jax.block_until_ready(run_batch(batch))
    seconds = time.perf_counter() - start
    instructions = num_machines * frames * machine.instructions_per_frame
    print(f"{num_machines} machines x {frames} frames in {seconds:.3f} s: "
          f"{num_machines * frames / seconds:,.0f} frames/s, {instructions / seconds:,.0f} instructions/s")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
