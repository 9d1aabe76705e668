"""Every SUPER-CHIP and XO-CHIP program of the Chip8 Community Archive runs the same on the JAX
core and on tests/reference.py, frame by frame, with the quirks and tick rate its programs.json
entry gives (Octo's option flags: `octax_core.emulator.quirks.quirks_from_octo`).

The keys follow a fixed schedule (held for 8 frames, then 8 frames free, each hold a new key) so
that menus are left and games move. The whole snapshot (RAM, registers, both planes, flags, mode,
plane selection, audio) must match after every frame.
"""

from __future__ import annotations

import json

import jax
import pytest
from reference import RefMachine, first_difference

import octax_core
from octax_core.emulator.quirks import quirks_from_octo
from octax_core.env.romstore import ARCHIVE_ROM_DIR as ARCHIVE  # the archive ships in the package

FRAMES = 120  # per program; programs that run 10,000 instructions a frame get a tenth


def archive_programs() -> dict:
    """The archive's SUPER-CHIP and XO-CHIP entries by name."""
    programs = json.loads((ARCHIVE / "programs.json").read_text())
    return {name: entry for name, entry in programs.items() if entry["platform"] in ("schip", "xochip")}


PROGRAMS = archive_programs()


def keys_at(frame: int) -> int:
    hold = frame // 8
    return 1 << (hold // 2 % 16) if hold % 2 else 0


def test_the_archive_has_its_53_modern_programs():
    assert len(PROGRAMS) == 53
    assert sorted({entry["platform"] for entry in PROGRAMS.values()}) == ["schip", "xochip"]


@pytest.mark.parametrize("name", PROGRAMS)
def test_program_matches_reference_frame_by_frame(name, jit_run_frames):
    entry = PROGRAMS[name]
    rom = (ARCHIVE / f"{name}.ch8").read_bytes()
    platform, options = entry["platform"], entry["options"]
    tickrate = int(options.get("tickrate", 20))
    machine = octax_core.Machine(platform, quirks=quirks_from_octo(options), instructions_per_frame=tickrate)
    state = machine.boot(rom, jax.random.key(0))
    ref = RefMachine(rom, machine.quirks, instructions_per_frame=tickrate, rng=int(state.rng), platform=platform)
    run = jit_run_frames(machine)
    lit = False
    for frame in range(FRAMES if tickrate <= 1000 else FRAMES // 10):
        keys = keys_at(frame)
        ref.run_frame(keys)
        state = run(state, keys, 1)
        snap = octax_core.snapshot(state)
        difference = first_difference(ref.snapshot(), snap)
        assert difference is None, f"{name} ({platform}, tickrate {tickrate}) frame {frame}, keys {keys:#06x}: {difference}"
        lit = lit or bool(snap["screen"].any())
    assert lit, f"{name} drew nothing: the comparison saw no pixels"
