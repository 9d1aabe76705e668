"""Differential test: the JAX core against tests/reference.py, frame by frame, on every ROM we have:
the octax suite's (from ../shared, or the ROM store), our own, and the test suite (../shared only).

Each ROM boots under both profiles, the reference takes the core's boot rng, and both run the
same scripted keys (stretches of nothing, single keys and random masks, changing every few
frames, so games that wait on FX0A move on). The whole snapshot must match after boot and after
every frame. On a mismatch the failing frame is replayed one instruction at a time to name the
first instruction that differs.
"""

import random
import zlib

import jax
import pytest
from reference import RefMachine, first_difference
from shared_data import REPO, TEST_SUITE_DIR, octax_rom_folder

import octax_core

OCTAX_ROMS = octax_rom_folder()
ROMS = ([pytest.param(path, id=path.stem[:24]) for path in sorted(OCTAX_ROMS.glob("*.ch8"))] if OCTAX_ROMS else []) + [
    pytest.param(path, id=path.stem[:24]) for path in sorted((REPO / "roms").glob("*.ch8"))] + [
    pytest.param(path, id=path.stem[:24], marks=pytest.mark.shared) for path in sorted(TEST_SUITE_DIR.glob("*.ch8"))]
PROFILES = ("chip8", "schip")
FRAMES = 240
INSTRUCTIONS_PER_FRAME = 11


def key_schedule(seed, frames):
    """A deterministic list of per-frame key masks: segments of 2..12 frames of one choice."""
    rng = random.Random(seed)
    masks = []
    while len(masks) < frames:
        roll = rng.random()
        if roll < 0.4:
            mask = 0
        elif roll < 0.8:
            mask = 1 << rng.randrange(16)
        else:
            mask = rng.randrange(1 << 16)
        masks += [mask] * rng.randint(2, 12)
    return masks[:frames]


def localize(execute, machine, state, ref, keys):
    """Replays one frame instruction by instruction from equal states; says where they part."""
    for step in range(machine.instructions_per_frame):
        pc = int(ref.pc)
        op = ref.execute(keys)
        state = execute(state, keys)
        difference = first_difference(ref.snapshot(), octax_core.snapshot(state))
        if difference:
            return f"instruction {step} of the frame, pc={pc:#05x} opcode={op:04X}: {difference}"
        if machine.quirks.display_wait and op >> 12 == 0xD:
            break
    return "all instructions of the frame agree: the difference is in the timer tick or the frame length"


def test_the_octax_roms_are_found():
    assert OCTAX_ROMS is not None, "no folder holds the octax suite's ROMs: run `octax-gym roms install`"
    assert len(list(OCTAX_ROMS.glob("*.ch8"))) >= 30


@pytest.mark.shared
def test_the_test_suite_is_found():
    assert len(list(TEST_SUITE_DIR.glob("*.ch8"))) >= 9


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("rom_path", ROMS)
def test_core_matches_reference(rom_path, profile, jit_run_frames, jit_execute):
    rom = rom_path.read_bytes()
    seed = zlib.crc32(rom_path.name.encode())
    machine = octax_core.Machine(quirks=profile, instructions_per_frame=INSTRUCTIONS_PER_FRAME)
    run = jit_run_frames(machine)
    state = machine.boot(rom, jax.random.key(seed))
    snap = octax_core.snapshot(state)
    ref = RefMachine(rom, machine.quirks, INSTRUCTIONS_PER_FRAME, rng=int(snap["rng"]))
    difference = first_difference(ref.snapshot(), snap)
    assert difference is None, f"{rom_path.name} [{profile}] after boot: {difference}"

    for frame, keys in enumerate(key_schedule(seed, FRAMES)):
        state_before, ref_before = state, ref.clone()
        ref_pc = ref.pc
        ref.run_frame(keys)
        state = run(state, keys, 1)
        snap = octax_core.snapshot(state)
        difference = first_difference(ref.snapshot(), snap)
        if difference:
            where = localize(jit_execute(machine), machine, state_before, ref_before, keys)
            rnd = " (RND ran in this frame)" if ref.rnd_ran else ""
            pytest.fail(
                f"{rom_path.name} [{profile}] frame {frame}{rnd}, keys={keys:#06x}, frame started at "
                f"pc={ref_pc:#05x} opcode={ref_before.fetch():04X}: "
                f"{difference}\n  first differing instruction: {where}"
            )
