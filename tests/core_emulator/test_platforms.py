"""SUPER-CHIP and XO-CHIP on the JAX core (issue 12): `Machine(platform=...)`.

Hand programs for every new opcode run on the core and on tests/reference.py, whose hand-worked
results test_reference_platforms.py checks, and must match after every instruction; then what is
the core's own: the platform config and its errors, the state's shape per platform (a CHIP-8
state keeps exactly its old fields), the host views, the exit, and batching.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from reference import BIG_FONT, RefMachine, assemble, first_difference

import octax_core
from octax_core.emulator.platforms import PLATFORMS
from octax_core.emulator.quirks import quirks_from_octo
from octax_core.emulator.state import shown

START = 0x200
ARROW = bytes([0x18, 0x3C, 0x7E, 0xFF, 0x18, 0x18, 0x18, 0x18])
SPRITE16 = bytes(range(0x81, 0xA1))  # 32 distinct bytes: a 16x16 sprite with no symmetry

# (name, platform, quirks, words, data, instructions): each opcode where it matters.
HAND_PROGRAMS = [
    ("lores-pixel-is-2x2", "schip", None, (0x6005, 0x6103, 0xA20C, 0xD011, 0x1208, 0x0000), b"\x80", 4),
    ("hires-pixel", "schip", None, (0x6005, 0x6103, 0xA20E, 0x00FF, 0xD011, 0x120A, 0x0000), b"\x80", 5),
    ("modes-clear", "schip", None, (0xA20A, 0xD004, 0x00FF, 0xD004, 0x00FE, 0x1208), ARROW, 6),
    ("dxy0-hires-collides", "schip", None, (0x00FF, 0x6079, 0x613A, 0xA20E, 0xD010, 0xD010, 0x120C), SPRITE16, 6),
    ("dxy0-lores", "schip", None, (0x6039, 0x611B, 0xA20A, 0xD010, 0x1208), SPRITE16, 4),
    ("clip-edges", "schip", None, (0x00FF, 0x607C, 0x613D, 0xA20C, 0xD018, 0x120A), ARROW, 5),
    ("wrap-edges", "schip", "xochip", (0x00FF, 0x607C, 0x613D, 0xA20C, 0xD018, 0x120A), ARROW, 5),
    ("wrap-lores-16", "schip", "xochip", (0x603A, 0x611C, 0xA20A, 0xD010, 0x1208), SPRITE16, 4),
    ("scrolls-hires", "schip", None,
     (0x00FF, 0x6021, 0x6113, 0xA21A, 0xD018, 0x00C3, 0x00FB, 0x00FB, 0x00FC, 0x00CF, 0x00CF, 0x00FC, 0x1218), ARROW, 13),
    ("scrolls-lores", "schip", None,
     (0x6021, 0x6113, 0xA218, 0xD018, 0x00C3, 0x00FB, 0x00FB, 0x00FC, 0x00C7, 0x00FC, 0x00FC, 0x1216), ARROW, 12),
    ("scroll-words", "schip", None,  # pixels crossing the 32-bit words of a row both ways
     (0x00FF, 0x601D, 0x6101, 0xA214, 0xD018, 0x00FB, 0x00FB, 0x00FC, 0x00FC, 0x1212), ARROW, 10),
    ("big-digits-flags", "schip", None,
     (0x6A0C, 0xFA30, 0x6000, 0x6100, 0xD015, 0x6007, 0x6109, 0xFF75, 0x6000, 0x6100, 0xF185, 0xFF85, 0x00FD, 0x6042),
     b"", 14),
    ("chip8-ignores-them", "chip8", None, (0x00FF, 0x00C3, 0x00FB, 0x00FD, 0x6A01, 0xFA30, 0xFA75, 0xF000, 0x5012, 0xF101),
     b"", 10),
    ("schip-ignores-xochip", "schip", None, (0x6001, 0xA300, 0xF000, 0x1234, 0x5012, 0x5013, 0xF101, 0xF002, 0x00D3, 0xF03A),
     b"", 10),
    ("long-i-and-skips", "xochip", None, (0x3000, 0xF000, 0x1234, 0x6001, 0x3001, 0xF000, 0xBEEF, 0x4000, 0x6002), b"", 6),
    ("ranges", "xochip", None, (0x6001, 0x6102, 0x6203, 0xA300, 0x5022, 0xA310, 0x5202, 0xA300, 0x5423, 0x5F03), b"", 10),
    ("64k-wrap", "xochip", None, (0xF000, 0xFFFE, 0x6107, 0x62FF, 0xF255, 0xF000, 0xFFFC, 0xF365, 0xF000, 0xFFF8, 0xD018),
     b"", 9),
    ("planes", "xochip", None,
     (0x00FF, 0xF301, 0xA214, 0xD002, 0xF201, 0x00C2, 0xF101, 0x00E0, 0xF001, 0xD002, 0x1212), bytes([0xF0, 0x0F, 0x3C, 0xC3]), 11),
    ("plane-2-alone-reads-first-bytes", "xochip", None, (0x00FF, 0xF201, 0xA20C, 0xD002, 0xF301, 0xD002), bytes([0xF0, 0x0F, 0x3C, 0xC3]), 6),
    ("both-planes-16x16", "xochip", None, (0xF301, 0x6030, 0x6110, 0xA20C, 0xD010, 0x120A), SPRITE16 + bytes(range(32)), 5),
    ("scroll-up-audio-pitch", "xochip", None,
     (0x00FF, 0x6005, 0x610A, 0xA216, 0xD011, 0x00D3, 0xA218, 0xF002, 0x6A30, 0xFA3A, 0x1214),
     bytes([0x80, 0x00]) + bytes(range(0x80, 0x90)), 10),
    ("unknown-plane", "xochip", None, (0xF401, 0xFF01, 0xF201), b"", 3),
]


def boot_both(platform, quirks, rom):
    machine = octax_core.Machine(platform, quirks=quirks)
    state = machine.boot(rom, jax.random.key(1))
    ref = RefMachine(rom, machine.quirks, rng=int(state.rng), platform=platform)
    return machine, state, ref


@pytest.mark.parametrize("name, platform, quirks, words, data, count", HAND_PROGRAMS, ids=[p[0] for p in HAND_PROGRAMS])
def test_hand_programs_match_reference(name, platform, quirks, words, data, count, jit_execute):
    rom = assemble(*words) + data
    machine, state, ref = boot_both(platform, quirks, rom)
    execute = jit_execute(machine)
    lit = False
    for step in range(count):
        pc = ref.pc
        ref.execute(0)
        state = execute(state, 0)
        snap = octax_core.snapshot(state)
        difference = first_difference(ref.snapshot(), snap)
        assert difference is None, f"{name}: instruction {step} at {pc:#06x}: {difference}"
        lit = lit or snap["screen"].any()
    assert lit == any(0xD000 <= w < 0xE000 for w in words), "a program that draws must light pixels"


def test_scrolls_move_what_the_contract_says(jit_execute):
    # hires: one pixel at (8, 8); down 3, right 4 -> (12, 11); lores: the 2x2 block moves twice as far
    for prefix, scale in ((0x00FF, 1), (0x00FE, 2)):
        machine = octax_core.Machine("schip")
        state = machine.boot(assemble(prefix, 0x6008, 0xA20E, 0xD001, 0x00C3, 0x00FB, 0x1210) + b"\x80", jax.random.key(0))
        for _ in range(6):
            state = jit_execute(machine)(state, 0)
        lit = set(zip(*np.nonzero(octax_core.snapshot(state)["screen"])))
        assert lit == {(11 * scale + j, 12 * scale + i) for i in range(scale) for j in range(scale)}


# ---- config and errors ----------------------------------------------------------------------------

def test_platforms_default_to_their_own_quirks_and_take_any():
    for name in PLATFORMS:
        assert octax_core.Machine(name).quirks == octax_core.QUIRK_PROFILES[name]
        assert octax_core.Machine(platform=name).platform.name == name
    machine = octax_core.Machine("xochip", quirks="chip8")
    assert machine.platform.name == "xochip" and machine.quirks == octax_core.QUIRK_PROFILES["chip8"]
    assert octax_core.Machine().platform.name == "chip8"


@pytest.mark.parametrize("bad", ["schip8", "SCHIP", "xo-chip", ""])
def test_unknown_platform_lists_the_valid_ones(bad):
    with pytest.raises(ValueError, match=r"unknown platform .*'chip8', 'schip', 'xochip'"):
        octax_core.Machine(bad)


def test_platform_of_the_wrong_type():
    with pytest.raises(TypeError, match="platform must be a platform name"):
        octax_core.Machine(2)


def test_rom_too_large_for_its_platform_names_both_sizes():
    rom = bytes(4000)
    with pytest.raises(ValueError, match=r"4000 bytes; a schip program .* at most 3584 bytes; it fits on xochip"):
        octax_core.Machine("schip").boot(rom, jax.random.key(0))
    with pytest.raises(ValueError, match=r"4000 bytes; a chip8 program .* at most 3584"):
        octax_core.Machine("chip8").boot(rom, jax.random.key(0))
    state = octax_core.Machine("xochip").boot(bytes(65024), jax.random.key(0))
    assert state.memory.shape == (32 + 65536 + 80,)
    with pytest.raises(ValueError, match=r"65025 bytes; .* 3584 bytes on chip8 and schip, 65024 on xochip"):
        octax_core.Rom(bytes(65025))


def test_xochip_opcodes_are_no_ops_on_chip8(jit_execute):
    # F000 NNNN is a 2-byte no-op (its address word then runs as an instruction: 6042)
    machine = octax_core.Machine("chip8")
    state = machine.boot(assemble(0xF000, 0x6042, 0x5012, 0x00FF, 0xF101), jax.random.key(0))
    before = octax_core.snapshot(state)
    for step in range(5):
        state = jit_execute(machine)(state, 0)
    after = octax_core.snapshot(state)
    assert int(after["pc"]) == START + 10 and int(after["V"][0]) == 0x42 and int(after["I"]) == 0
    assert np.array_equal(before["memory"], after["memory"]) and not after["screen"].any()


# ---- state and host views -------------------------------------------------------------------------

def state_bytes(state) -> int:
    return sum(leaf.nbytes for leaf in jax.tree.leaves(state))


def test_a_chip8_state_keeps_its_fields_and_size():
    state = octax_core.Machine("chip8").boot(b"\x12\x00", jax.random.key(0))
    assert len(jax.tree.leaves(state)) == 11
    assert [f.name for f in dataclasses.fields(state) if getattr(state, f.name) is None] == ["extension"]
    assert state.memory.shape == (4192,) and state.screen.shape == (32, 2)
    assert state_bytes(state) == 4192 + 16 + 2 + 2 + 1 + 32 + 1 + 1 + 256 + 4 + 1


def test_state_shapes_per_platform():
    schip = octax_core.Machine("schip").boot(b"\x12\x00", jax.random.key(0))
    xochip = octax_core.Machine("xochip").boot(b"\x12\x00", jax.random.key(0))
    # the 64x32 lores picture per plane in `screen`, as on CHIP-8; the 128x64 hires grid in the extension
    assert schip.memory.shape == (4208,) and schip.screen.shape == (1, 32, 2) and schip.extension.grid.shape == (1, 64, 4)
    assert xochip.memory.shape == (65648,) and xochip.screen.shape == (2, 32, 2) and xochip.extension.grid.shape == (2, 64, 4)
    # one optional part, the same on both: SUPER-CHIP's plane is always 1, its audio never set
    assert [f.name for f in dataclasses.fields(schip.extension)] == [
        "hires", "grid", "flags", "exited", "plane", "audio_pattern", "pitch"]
    assert int(schip.extension.plane) == 1
    assert state_bytes(schip) == 4208 + 16 + 2 + 2 + 1 + 32 + 1 + 1 + 256 + 4 + 1 + 1 + 1024 + 16 + 1 + 1 + 16 + 1
    assert state_bytes(xochip) == 65648 + 16 + 2 + 2 + 1 + 32 + 1 + 1 + 512 + 4 + 1 + 1 + 2048 + 16 + 1 + 1 + 16 + 1
    snap = octax_core.snapshot(xochip)
    assert snap["memory"].shape == (65536,) and snap["screen"].shape == (2, 64, 128)
    assert int(snap["plane"]) == 1 and int(snap["pitch"]) == 64 and snap["audio_pattern"].shape == (16,)
    assert bytes(snap["memory"][0xA0:0xA0 + 160]) == BIG_FONT  # the big digits, where the contract puts them
    snap = octax_core.snapshot(schip)
    assert snap["screen"].shape == (64, 128) and "plane" not in snap and not snap["hires"] and not snap["exited"]


def run_instructions(execute, state, count):
    for _ in range(count):
        state = execute(state, 0)
    return state


def test_render_text_per_platform(jit_execute):
    # a hires pixel at (3, 1) on plane 1, (4, 1) on plane 2, (5, 1) on both (the hand programs'
    # compiled `execute` runs the 12 instructions)
    rom = assemble(0x00FF, 0x6003, 0x6101, 0xA21A, 0xF101, 0xD011, 0x6004, 0xF201, 0xD011, 0x6005, 0xF301, 0xD011,
                   0x1218) + b"\x80\x80"
    machine = octax_core.Machine("xochip")
    state = run_instructions(jit_execute(machine), machine.boot(rom, jax.random.key(0)), 12)
    lines = octax_core.render_text(state).splitlines()
    assert len(lines) == 64 and {len(line) for line in lines} == {128}
    assert lines[1][:8] == "...123.." and set("".join(lines[2:])) == {"."}
    schip = octax_core.Machine("schip")
    text = octax_core.render_text(run_instructions(
        jit_execute(schip), schip.boot(assemble(0xA20A, 0xD001, 0x1204, 0, 0) + b"\x80", jax.random.key(0)), 2))
    assert text.splitlines()[0][:3] == "##." and text.splitlines()[1][:3] == "##." and len(text.splitlines()) == 64
    batch = jax.vmap(schip.boot, in_axes=(None, 0))(b"\x12\x00", jax.random.split(jax.random.key(0), 2))
    with pytest.raises(ValueError, match="one machine's state"):
        octax_core.render_text(batch)


def test_poke_on_xochip_reaches_high_memory_and_keeps_the_mirror():
    machine = octax_core.Machine("xochip")
    state = octax_core.poke(machine.boot(b"\x12\x00", jax.random.key(0)), 0xFFFE, bytes([1, 2, 3, 4]))
    ram = octax_core.snapshot(state)["memory"]
    assert list(ram[0xFFFE:]) == [1, 2] and list(ram[:2]) == [3, 4]
    assert list(np.asarray(state.memory)[32 + 65536:32 + 65536 + 64]) == list(ram[:64])


# ---- exit, frames, batches ------------------------------------------------------------------------

def test_exit_stands_still_and_an_env_can_read_it(jit_run_frames):
    # delay := 10; 00FD: the exit's own frame ticks the timer, later frames change nothing
    # (one frame a call, as the recorded-screens test below runs it: one compile for both)
    machine = octax_core.Machine("schip", instructions_per_frame=5)
    state = machine.boot(assemble(0x600A, 0xF015, 0x00FD, 0x6142), jax.random.key(0))

    def run(state, keys):
        return jit_run_frames(machine)(state, jnp.uint32(keys), 1, halted=jnp.bool_(False))

    state = run(state, 0)
    assert bool(state.exited) and int(state.pc) == START + 4 and int(state.delay_timer) == 9
    later = state
    for _ in range(5):
        later = run(later, 0xFFFF)
    assert all(np.array_equal(a, b) for a, b in zip(jax.tree.leaves(state), jax.tree.leaves(later)))


def test_batches_run_each_machine_as_alone(jit_run_frames, jit_batch_run_frames):
    # random sprites and scrolls; the same key gives the same machine whatever the batch
    # (4 one-frame calls of 6 machines: test_one_machine.py's plane-2 test's programs, one compile for both)
    rom = assemble(0x00FF, 0xF301, 0xC0FF, 0xC1FF, 0xA200, 0xD010, 0x00C1, 0x00FB, 0x1204)
    machine = octax_core.Machine("xochip", instructions_per_frame=30)
    keys = jax.random.split(jax.random.key(7), 6)
    batch = jax.vmap(lambda k: machine.boot(rom, k))(keys)
    for _ in range(4):
        batch = jit_batch_run_frames(machine, 1)(batch, jnp.zeros(6, jnp.uint32))
    for i in range(6):
        alone = machine.boot(rom, keys[i])
        for _ in range(4):
            alone = jit_run_frames(machine)(alone, 0, 1)
        for a, b in zip(jax.tree.leaves(alone), jax.tree.leaves(batch)):
            assert np.array_equal(np.asarray(a), np.asarray(b)[i])
    assert octax_core.snapshot(batch)["screen"].shape == (6, 2, 64, 128)
    assert len({bytes(np.asarray(grid)) for grid in batch.extension.grid}) > 1  # each key drew its own (hires) picture


def test_record_screens_has_the_platform_shape():
    machine = octax_core.Machine("schip")  # the traced program's output, without compiling it
    state, screens = jax.eval_shape(lambda s: machine.run_frames(s, 0, 3, record_screens=True),
                                    machine.boot(b"\x12\x00", jax.random.key(0)))
    assert screens.shape == (3, 1, 64, 4) and screens.dtype == jnp.uint32


def test_recorded_screens_are_each_frames_picture_through_an_exit_and_a_halt(jit_run_frames):
    # One recorded call of 5 frames equals 5 one-frame calls, picture by picture, for a batch of
    # a machine that exits in its fourth frame (key A held: the frames after show its last
    # picture), one that runs on drawing (no key), and one halted (all five show its picture).
    rom = assemble(0x6A0A, 0xA212, 0x7004, 0xD011, 0xEA9E, 0x1204, 0x4010, 0x00FD, 0x1204) + b"\x80"
    machine = octax_core.Machine("schip", instructions_per_frame=5)
    keys = jnp.array([1 << 0xA, 0, 0], jnp.uint32)
    halted = jnp.array([False, False, True])

    def one(state, keys, halted):
        return jit_run_frames(machine)(state, keys, 1, halted=halted)

    boot = [one(machine.boot(rom, k), key, jnp.bool_(False))
            for k, key in zip(jax.random.split(jax.random.key(3), 3), jnp.array([0, 0, 1 << 0xA], jnp.uint32))]
    boot = jax.tree.map(lambda *leaves: jnp.stack(leaves), *boot)
    state, screens = jax.jit(jax.vmap(lambda s, k, h: machine.run_frames(s, k, 5, halted=h, record_screens=True)))(
        boot, keys, halted)
    for i in range(3):
        alone = jax.tree.map(lambda leaf: leaf[i], boot)
        for frame in range(5):
            alone = one(alone, keys[i], halted[i])
            assert np.array_equal(np.asarray(screens[i, frame]), np.asarray(shown(alone))), (i, frame)
        assert bool(alone.exited) == (i == 0)
        assert all(np.array_equal(np.asarray(a), np.asarray(b)[i])
                   for a, b in zip(jax.tree.leaves(alone), jax.tree.leaves(state)))
    assert not np.array_equal(np.asarray(screens[0, 1]), np.asarray(screens[0, 2]))  # it drew on its way
    assert np.array_equal(np.asarray(screens[0, 3]), np.asarray(screens[0, 4]))
    assert np.asarray(screens[2]).any()  # the halted machine's picture is not blank


# ---- Octo's option flags ----------------------------------------------------------------------------

def test_quirks_from_octo_flags():
    assert quirks_from_octo({}) == octax_core.Quirks(vf_reset=False, memory_increment=True, display_wait=False,
                                                     clipping=False, shift_uses_vy=True, jump_uses_vx=False)
    flags = {"shiftQuirks": 1, "loadStoreQuirks": True, "clipQuirks": True, "jumpQuirks": 1, "vBlankQuirks": True,
             "logicQuirks": True, "vfOrderQuirks": 0, "tickrate": "20", "fillColor": "#FFFFFF"}
    assert quirks_from_octo(flags) == octax_core.Quirks(vf_reset=True, memory_increment=False, display_wait=True,
                                                        clipping=True, shift_uses_vy=False, jump_uses_vx=True)
    with pytest.raises(ValueError, match="vfOrderQuirks"):
        quirks_from_octo({"vfOrderQuirks": True})
    with pytest.raises(ValueError, match="clipQuirks must be true, false, 1 or 0, got 'yes'"):
        quirks_from_octo({"clipQuirks": "yes"})
