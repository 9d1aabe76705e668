"""Every SUPER-CHIP and XO-CHIP program of the Chip8 Community Archive runs the same on the JAX
core and on tests/reference.py, frame by frame, with the quirks and tick rate its programs.json
entry gives (Octo's option flags: `octax_core.emulator.quirks.quirks_from_octo`).

The keys follow a fixed schedule (held for 8 frames, then 8 frames free, each hold a new key) so
that menus are left and games move. The whole snapshot (RAM, registers, both planes, flags, mode,
plane selection, audio) must match after every frame.

Each program's machine config (platform, quirks, tick rate) is its own compiled program (programs
of one config share it), so `make test` runs a representative subset, `FAST`, of one config per
(platform, quirks) profile of the archive: every profile (a test below checks that), both frame
loops (under 25 instructions a frame, and idle skipping from 25), and what the programs do in
their first 120 frames on the reference: hires and the mode switches, 16x16 sprites in both
modes, scrolling, XO-CHIP's plane 2 and both planes, long I beyond 4 KiB, register ranges, audio
patterns, big digits, flag registers, BCD, BNNN, CXNN and FX0A. (dodge, whose lores scroll down
was the subset's only one, and t8nks each needed a config of their own; the hand programs of
test_platforms.py and the random programs check those opcodes against the reference.)
`make test-slow` runs all 53.
"""

from __future__ import annotations

import json

import jax
import pytest
from reference import RefMachine, first_difference

import octax_core
from octax_core.emulator.idle import SKIP_FROM
from octax_core.emulator.quirks import quirks_from_octo
from octax_core.env.romstore import ARCHIVE_ROM_DIR as ARCHIVE  # the archive ships in the package

FRAMES = 120  # per program; programs that run 10,000 instructions a frame get a tenth


def archive_programs() -> dict:
    """The archive's SUPER-CHIP and XO-CHIP entries by name."""
    programs = json.loads((ARCHIVE / "programs.json").read_text())
    return {name: entry for name, entry in programs.items() if entry["platform"] in ("schip", "xochip")}


PROGRAMS = archive_programs()

# name: what it adds (in its first 120 frames on tests/reference.py)
FAST = {
    "DVN8": "schip, Octo's default quirks, 20 ipf (the plain frame loop): big digits, 16x16 hires sprites",
    "chipcross": "the same compiled program: flag registers, BCD, FX0A",
    "sens8tion": "schip, its own quirks (no increment, shift and jump by VX): hires and lores switches, lores 16x16",
    "octogon": "schip, the SUPER-CHIP profile, 200 ipf: lores 16x16 sprites",
    "binding": "schip, Octo's defaults with clipping, 1000 ipf: 16x16 hires sprites, BCD, CXNN",
    "flutterby": "xochip, Octo's defaults, 7 ipf (the plain frame loop): plane 2 in hires, audio pattern, CXNN",
    "skyward": "xochip, Octo's defaults without increment, 1000 ipf: scrolling down in hires, both planes, audio, "
               "ranges, long I, BNNN",
    "superneatboy": "xochip, Octo's defaults with clipping, 1000 ipf: both planes, 16x16 hires sprites, long I, "
                    "ranges, audio",
}


def keys_at(frame: int) -> int:
    hold = frame // 8
    return 1 << (hold // 2 % 16) if hold % 2 else 0


def test_the_archive_has_its_53_modern_programs():
    assert len(PROGRAMS) == 53
    assert sorted({entry["platform"] for entry in PROGRAMS.values()}) == ["schip", "xochip"]


def profile(entry) -> tuple:
    return entry["platform"], quirks_from_octo(entry["options"])


def test_the_fast_subset_has_every_platform_and_quirk_profile_of_the_archive():
    assert set(FAST) <= set(PROGRAMS)
    assert {profile(PROGRAMS[name]) for name in FAST} == {profile(entry) for entry in PROGRAMS.values()}
    configs = {(*profile(PROGRAMS[name]), int(PROGRAMS[name]["options"].get("tickrate", 20))) for name in FAST}
    assert len(configs) == len({profile(entry) for entry in PROGRAMS.values()})  # one compiled program a profile
    rates = {int(PROGRAMS[name]["options"].get("tickrate", 20)) for name in FAST}
    assert min(rates) < SKIP_FROM <= max(rates)  # both frame loops: plain, and idle skipping


@pytest.mark.parametrize("name", [name if name in FAST else pytest.param(name, marks=pytest.mark.slow)
                                  for name in PROGRAMS])
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
