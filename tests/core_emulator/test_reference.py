"""The reference interpreter's own tests: hand-computed expectations from docs/machine.md.

The differential tests trust `tests/reference.py`; these tests are why. Each builds a tiny
program, runs it on the reference only, and checks registers, memory and screen by hand.
"""

import numpy as np
import pytest
from reference import FONT_ADDRESS, NO_KEY, PROFILES, RefMachine, RefQuirks, assemble, xorshift32

START_PC = 0x200
OPCODE_SIZE = 2
NEXT_PC = START_PC + OPCODE_SIZE
SKIPPED_PC = START_PC + 2 * OPCODE_SIZE

WRAPPING = RefQuirks(vf_reset=False, memory_increment=False, display_wait=False,
                     clipping=False, shift_uses_vy=False, jump_uses_vx=False)


def run(*words, quirks="chip8", keys=0, rng=1):
    """Runs each word of the program once, in order, and returns the machine."""
    machine = RefMachine(assemble(*words), quirks, rng=rng)
    for _ in words:
        machine.execute(keys)
    return machine


def lit(machine):
    """The set of lit (x, y) pixels."""
    return {(x, y) for y, row in enumerate(machine.screen) for x, on in enumerate(row) if on}


def test_boot_image():
    machine = RefMachine(b"\x12\x00", "chip8", rng=7)
    snap = machine.snapshot()
    assert snap["pc"] == START_PC and snap["I"] == 0 and snap["sp"] == 0
    assert snap["key_wait"] == NO_KEY and snap["rng"] == 7
    assert bytes(snap["memory"][FONT_ADDRESS:FONT_ADDRESS + 5]) == bytes([0xF0, 0x90, 0x90, 0x90, 0xF0])
    assert bytes(snap["memory"][0x9B:0xA0]) == bytes([0xF0, 0x80, 0xF0, 0x80, 0x80])  # "F"
    assert snap["memory"][0xA0] == 0
    assert bytes(snap["memory"][0x200:0x202]) == b"\x12\x00"


def test_snapshot_dtypes_and_shapes():
    snap = RefMachine(b"\x00\xe0", "schip").snapshot()
    expected = {
        "memory": ((4096,), np.uint8), "V": ((16,), np.uint8), "I": ((), np.uint16),
        "pc": ((), np.uint16), "sp": ((), np.uint8), "stack": ((16,), np.uint16),
        "delay_timer": ((), np.uint8), "sound_timer": ((), np.uint8),
        "screen": ((32, 64), np.bool_), "rng": ((), np.uint32), "key_wait": ((), np.uint8),
    }
    assert set(snap) == set(expected)
    for name, (shape, dtype) in expected.items():
        assert snap[name].shape == shape and snap[name].dtype == dtype, name


def test_xorshift32_known_sequence():
    # Marsaglia's xorshift32 (13, 17, 5) from seed 1.
    values = [xorshift32(1)]
    values.append(xorshift32(values[-1]))
    values.append(xorshift32(values[-1]))
    assert values == [270369, 67634689, 2647435461]


def test_cxnn_takes_top_byte_of_xorshift():
    machine = run(0xC0FF, 0xC1FF, 0xC2F0)
    assert machine.V[:3] == [0, 4, 0x9D & 0xF0]
    assert machine.rng == 2647435461


@pytest.mark.parametrize("vx, vy, expected_vf", [(0xF0, 0x20, 1), (0xF0, 0x05, 0)])
def test_8xy4_with_x_f_leaves_the_carry_in_vf(vx, vy, expected_vf):
    machine = run(0x6F00 | vx, 0x6100 | vy, 0x8F14)
    assert machine.V[0xF] == expected_vf


def test_8xy4_sum_and_carry():
    machine = run(0x60FF, 0x6102, 0x8014)
    assert (machine.V[0], machine.V[0xF]) == (0x01, 1)


@pytest.mark.parametrize("vx, vy, diff, vf", [(5, 10, 0xFB, 0), (10, 5, 5, 1), (7, 7, 0, 1)])
def test_8xy5_borrow(vx, vy, diff, vf):
    machine = run(0x6000 | vx, 0x6100 | vy, 0x8015)
    assert (machine.V[0], machine.V[0xF]) == (diff, vf)


def test_8xy5_with_x_f_leaves_the_flag_in_vf():
    machine = run(0x6F05, 0x610A, 0x8F15)
    assert machine.V[0xF] == 0


def test_8xy7_reverse_subtract():
    machine = run(0x6005, 0x610A, 0x8017)
    assert (machine.V[0], machine.V[0xF]) == (5, 1)
    machine = run(0x600A, 0x6105, 0x8017)
    assert (machine.V[0], machine.V[0xF]) == (0xFB, 0)


@pytest.mark.parametrize("profile, v0, vf", [("chip8", 1, 1), ("schip", 0, 1)])
def test_8xy6_shift_source_follows_shift_uses_vy(profile, v0, vf):
    machine = run(0x6001, 0x6103, 0x8016, quirks=profile)
    assert (machine.V[0], machine.V[0xF]) == (v0, vf)


@pytest.mark.parametrize("profile, v0, vf", [("chip8", 0x80, 0), ("schip", 0x02, 1)])
def test_8xye_shift_source_follows_shift_uses_vy(profile, v0, vf):
    machine = run(0x6081, 0x6140, 0x801E, quirks=profile)
    assert (machine.V[0], machine.V[0xF]) == (v0, vf)


@pytest.mark.parametrize("op, result", [(0x8011, 0x07), (0x8012, 0x01), (0x8013, 0x06)])
@pytest.mark.parametrize("profile, vf", [("chip8", 0), ("schip", 0x05)])
def test_logic_ops_and_vf_reset(op, result, profile, vf):
    machine = run(0x6F05, 0x6003, 0x6105, op, quirks=profile)
    assert (machine.V[0], machine.V[0xF]) == (result, vf)


def test_7xnn_wraps_without_touching_vf():
    machine = run(0x60FF, 0x7002)
    assert (machine.V[0], machine.V[0xF]) == (1, 0)


def test_fx33_bcd():
    machine = run(0x60FE, 0xA300, 0xF033)
    assert list(machine.memory[0x300:0x303]) == [2, 5, 4]
    assert machine.I == 0x300


def test_fx33_wraps_at_4k():
    machine = run(0x607B, 0xAFFF, 0xF033)
    assert (machine.memory[0xFFF], machine.memory[0], machine.memory[1]) == (1, 2, 3)


@pytest.mark.parametrize("profile, final_i", [("chip8", 0x303), ("schip", 0x300)])
def test_fx55_fx65_and_memory_increment(profile, final_i):
    machine = run(0x6011, 0x6122, 0x6233, 0xA300, 0xF255, quirks=profile)
    assert list(machine.memory[0x300:0x304]) == [0x11, 0x22, 0x33, 0]
    assert machine.I == final_i
    machine = run(0xA200, 0xF165, quirks=profile)  # loads its own first two bytes
    assert machine.V[:3] == [0xA2, 0x00, 0]
    assert machine.I == {"chip8": 0x202, "schip": 0x200}[profile]


def test_fx1e_wraps_and_leaves_vf():
    machine = run(0xAFFF, 0x6002, 0xF01E)
    assert (machine.I, machine.V[0xF]) == (1, 0)


def test_fx29_points_at_the_font():
    machine = run(0x601A, 0xF029)
    assert machine.I == FONT_ADDRESS + 5 * 0xA


def test_draw_and_collision():
    machine = run(0xA050, 0x6000, 0x6100, 0xD015)  # the "0" glyph at (0, 0)
    assert machine.V[0xF] == 0
    zero = {(0, 0), (1, 0), (2, 0), (3, 0), (0, 1), (3, 1), (0, 2), (3, 2),
            (0, 3), (3, 3), (0, 4), (1, 4), (2, 4), (3, 4)}
    assert lit(machine) == zero
    machine.memory[0x208:0x20A] = assemble(0xD015)
    machine.execute(0)
    assert machine.V[0xF] == 1
    assert lit(machine) == set()


def test_draw_with_vf_as_coordinate_sets_the_flag_after():
    machine = run(0xA050, 0x6F00, 0xDFF1, 0xDFF1)  # second draw reads VF = 0, erases, VF = 1
    assert machine.V[0xF] == 1
    assert lit(machine) == set()


def test_draw_start_position_wraps():
    machine = run(0xA050, 0x6041, 0x6122, 0xD011)  # (65, 34) -> (1, 2)
    assert lit(machine) == {(1, 2), (2, 2), (3, 2), (4, 2)}


def test_draw_with_n_zero_draws_nothing():
    machine = run(0xA050, 0xD010)
    assert (machine.V[0xF], lit(machine)) == (0, set())


def test_clipping_drops_pixels_past_the_edges():
    machine = run(0xA050, 0x603E, 0x611E, 0xD015)  # "0" at (62, 30)
    assert lit(machine) == {(62, 30), (63, 30), (62, 31)}


def test_without_clipping_pixels_wrap():
    machine = run(0xA050, 0x603E, 0x611E, 0xD015, quirks=WRAPPING)
    expected = {(62, 30), (63, 30), (0, 30), (1, 30),  # F0
                (62, 31), (1, 31), (62, 0), (1, 0), (62, 1), (1, 1),  # 90 x3
                (62, 2), (63, 2), (0, 2), (1, 2)}  # F0
    assert lit(machine) == expected


def test_clear_screen():
    machine = run(0xA050, 0xD005, 0x00E0)
    assert lit(machine) == set()


def test_call_and_return():
    machine = RefMachine(assemble(0x2206, 0x0000, 0x0000, 0x00EE), "chip8")
    machine.execute(0)
    assert (machine.pc, machine.sp) == (0x206, 1)
    assert machine.stack[0] == NEXT_PC
    machine.execute(0)
    assert (machine.pc, machine.sp) == (NEXT_PC, 0)


def test_stack_wraps_after_16_calls():
    machine = RefMachine(assemble(0x2200), "chip8")
    for _ in range(17):
        machine.execute(0)
    assert machine.sp == 1
    assert machine.stack == [NEXT_PC] * 16


def test_return_on_empty_stack_wraps_to_entry_15():
    machine = run(0x00EE)
    assert (machine.sp, machine.pc) == (15, 0)


@pytest.mark.parametrize("op, v, skipped", [
    (0x3042, 0x42, True), (0x3042, 0x41, False),
    (0x4042, 0x42, False), (0x4042, 0x41, True),
])
def test_skip_on_immediate(op, v, skipped):
    machine = run(0x6000 | v, op)  # the skip runs at NEXT_PC
    assert machine.pc == NEXT_PC + (2 * OPCODE_SIZE if skipped else OPCODE_SIZE)


def test_skip_on_registers():
    assert run(0x6005, 0x6105, 0x5010).pc == NEXT_PC + 6
    assert run(0x6005, 0x6106, 0x5010).pc == NEXT_PC + 4
    assert run(0x6005, 0x6106, 0x9010).pc == NEXT_PC + 6
    assert run(0x6005, 0x6105, 0x5011).pc == NEXT_PC + 4  # 5XY1 is not a skip


def test_skip_wraps_at_4k():
    machine = RefMachine(b"\x00\x00", "chip8")
    machine.memory[0xFFE:0x1000] = assemble(0x3000)
    machine.pc = 0xFFE
    machine.execute(0)
    assert machine.pc == 0x002


def test_fetch_wraps_at_4k():
    machine = RefMachine(b"\x00\x00", "chip8")
    machine.memory[0xFFF] = 0x60
    machine.memory[0x000] = 0x42
    machine.pc = 0xFFF
    machine.execute(0)
    assert (machine.V[0], machine.pc) == (0x42, 0x001)


def test_bnnn_uses_v0_on_chip8_and_wraps():
    assert run(0x6002, 0x6305, 0xB300).pc == 0x302
    assert run(0x60FF, 0xBFFF).pc == (0xFFF + 0xFF) & 0xFFF


def test_bnnn_uses_vx_with_jump_uses_vx():
    assert run(0x6002, 0x6305, 0xB310, quirks="schip").pc == 0x315


@pytest.mark.parametrize("op, held, expected_pc", [
    (0xE59E, True, SKIPPED_PC), (0xE59E, False, NEXT_PC),
    (0xE5A1, True, NEXT_PC), (0xE5A1, False, SKIPPED_PC),
])
def test_key_skips_use_low_nibble_of_vx(op, held, expected_pc):
    machine = RefMachine(assemble(op), "chip8")
    machine.V[5] = 0xF7  # key 7
    machine.execute(1 << 7 if held else 1 << 6)
    assert machine.pc == expected_pc


def test_fx0a_waits_for_press_then_release():
    machine = RefMachine(assemble(0xF30A), "chip8")
    machine.execute(0)
    assert (machine.pc, machine.key_wait) == (START_PC, NO_KEY)
    machine.execute((1 << 5) | (1 << 7))  # lowest held key is remembered
    assert (machine.pc, machine.key_wait) == (START_PC, 5)
    machine.execute(1 << 5)
    assert (machine.pc, machine.key_wait) == (START_PC, 5)
    machine.execute(1 << 7)  # key 5 released, 7 still held: done
    assert (machine.pc, machine.key_wait, machine.V[3]) == (NEXT_PC, NO_KEY, 5)


def test_keys_as_bools():
    machine = RefMachine(assemble(0xE09E), "chip8")
    machine.execute([True] + [False] * 15)
    assert machine.pc == SKIPPED_PC


def test_timers_tick_once_per_frame_and_fx07_reads_them():
    machine = RefMachine(assemble(0x600A, 0xF015, 0xF018, 0x1206), "schip")
    machine.run_frame(0)
    assert (machine.delay_timer, machine.sound_timer) == (9, 9)
    machine.run_frames(0, 20)
    assert (machine.delay_timer, machine.sound_timer) == (0, 0)
    machine = RefMachine(assemble(0x6005, 0xF015, 0xF107, 0x1206), "schip")
    machine.run_frame(0)
    machine.memory[0x206:0x208] = assemble(0xF207)
    machine.execute(0)
    assert (machine.V[1], machine.V[2]) == (5, 4)


@pytest.mark.parametrize("profile, executed", [("chip8", 2), ("schip", 11)])
def test_display_wait_ends_the_frame_after_a_draw(profile, executed):
    program = assemble(0xA050, 0xD001, *[0x7001] * 20)
    machine = RefMachine(program, profile, instructions_per_frame=11)
    machine.run_frame(0)
    assert machine.pc == START_PC + OPCODE_SIZE * executed


def test_rnd_ran_is_per_frame():
    machine = RefMachine(assemble(0xC0FF, 0x1202), "schip")
    machine.run_frame(0)
    assert machine.rnd_ran
    machine.run_frame(0)
    assert not machine.rnd_ran


@pytest.mark.parametrize("op", [0x0123, 0x00E1, 0x00FF, 0x5121, 0x9121, 0x8018, 0x801F,
                                0xE09F, 0xF0FF, 0xF075, 0xF085, 0xF030])
def test_unknown_opcodes_are_no_ops(op):
    machine = RefMachine(assemble(0x6142, 0xA123, op), "chip8")
    machine.execute(0)
    machine.execute(0)
    before = machine.snapshot()
    machine.execute(0xFFFF)
    after = machine.snapshot()
    assert after["pc"] == before["pc"] + 2
    for name in before:
        if name != "pc":
            np.testing.assert_array_equal(after[name], before[name], err_msg=name)


def test_profiles_match_the_doc_table():
    assert PROFILES["chip8"] == RefQuirks(True, True, True, True, True, False)
    assert PROFILES["schip"] == RefQuirks(False, False, False, True, False, True)
    assert PROFILES["xochip"] == RefQuirks(False, True, False, False, True, False)


def test_profiles_are_the_cores():
    """The oracle's profiles are written apart from the core's, so compare them field by field."""
    import dataclasses

    import octax_core

    assert set(PROFILES) == set(octax_core.QUIRK_PROFILES)
    for name, quirks in octax_core.QUIRK_PROFILES.items():
        assert dataclasses.asdict(quirks) == dataclasses.asdict(PROFILES[name]), name


def test_clone_is_independent():
    machine = run(0xA050, 0x6001, 0x6100, 0xD015)
    other = machine.clone()
    other.execute(0)  # runs 0000 (no-op) on the clone only
    other.V[0] = 9
    other.memory[0x300] = 1
    other.screen[0][0] = not other.screen[0][0]
    other.stack[0] = 5
    assert (machine.V[0], machine.memory[0x300], machine.stack[0], machine.pc) == (1, 0, 0, 0x208)
    assert machine.screen[0][1] and not machine.screen[0][0]
