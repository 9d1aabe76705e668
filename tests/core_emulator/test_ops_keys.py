"""Key opcodes: EX9E, EXA1 and FX0A (press, then release, as on the COSMAC VIP)."""


import numpy as np
import pytest
from chip_builder import NEXT, SKIPPED, START, hexid

NO_KEY = 0xFF


def held(*keys):
    return sum(1 << k for k in keys)


SKP = [  # (V1, keys held, key V1 & 0xF is held)
    (0x5, held(5), True), (0x5, held(4), False), (0x5, 0, False), (0x5, 0xFFFF, True),
    (0x5, 0xFFFF & ~held(5), False), (0x35, held(5), True), (0xF0, held(0), True), (0xF, held(15), True),
]


@pytest.mark.parametrize("profile", ["chip8", "schip"])
@pytest.mark.parametrize("v1, keys, is_held", SKP, ids=hexid)
def test_ex9e_and_exa1(chip, profile, v1, keys, is_held):
    assert chip([0xE19E], profile, V={1: v1}).step(keys).pc == (SKIPPED if is_held else NEXT)
    assert chip([0xE1A1], profile, V={1: v1}).step(keys).pc == (NEXT if is_held else SKIPPED)


def test_keys_as_bool_array(chip):
    keys = np.zeros(16, bool)
    keys[0xC] = True
    assert chip([0xE19E], V={1: 0xC}).step(keys).pc == SKIPPED
    assert chip([0xE19E], V={1: 0xB}).step(keys).pc == NEXT
    assert chip([0xE1A1], V={1: 0xB}).step(keys).pc == SKIPPED


def test_ef9e_uses_vf(chip):
    assert chip([0xEF9E], V={0xF: 7}).step(held(7)).pc == SKIPPED


def test_key_ops_change_nothing_else(chip):
    c = chip([0xE19E], V={1: 3, 0xF: 0x55})
    before = c.snapshot()
    after = c.step(held(3)).snapshot()
    assert [k for k in before if k != "pc" and not np.array_equal(before[k], after[k])] == []


def test_fx0a_waits_for_press_then_release(chip):
    c = chip([0xF10A, 0x1202], V={1: 0xEE})
    steps = [  # (keys held, pc after, key_wait after, V1 after)
        (0, START, NO_KEY, 0xEE),            # nothing pressed: wait
        (0, START, NO_KEY, 0xEE),
        (held(5, 9), START, 5, 0xEE),        # the lowest held key is remembered
        (held(5), START, 5, 0xEE),           # still held: wait
        (held(2, 5), START, 5, 0xEE),        # another key does not replace it
        (held(2, 9), NEXT, NO_KEY, 0x5),     # 5 released: V1 = 5, go on
    ]
    for keys, pc, key_wait, v1 in steps:
        c.step(keys)
        assert (c.pc, c.key_wait, c.V[1]) == (pc, key_wait, v1), f"keys {keys:#06x}"


def test_fx0a_key_zero(chip):
    c = chip([0xF30A]).step(held(0))
    assert (c.pc, c.key_wait) == (START, 0)
    c.step(0)
    assert (c.pc, c.V[3]) == (NEXT, 0)


def test_fx0a_into_vf(chip):
    c = chip([0xFF0A], V={0xF: 0xAA}).step(held(0xB)).step(0)
    assert (c.pc, c.V[0xF]) == (NEXT, 0xB)


def test_back_to_back_fx0a_needs_a_new_press(chip):
    # A key still held when the second FX0A starts counts as a fresh press: it must be released again.
    c = chip([0xF10A, 0xF20A, 0x1204]).step(held(4)).step(held(6))
    assert (c.pc, c.V[1]) == (NEXT, 4)
    c.step(held(6))
    assert (c.pc, c.key_wait) == (NEXT, 6)
    c.step(held(6))
    assert c.pc == NEXT
    c.step(0)
    assert (c.pc, c.V[2]) == (SKIPPED, 6)


def test_fx0a_leaves_other_state_alone_while_waiting(chip):
    c = chip([0xF10A], V={r: r for r in range(16)}, I=0x123, delay_timer=9)
    before = c.snapshot()
    after = c.step(0).step(held(1)).snapshot()
    assert [k for k in before if k != "key_wait" and not np.array_equal(before[k], after[k])] == []


def test_timers_run_while_fx0a_waits(chip):
    c = chip([0xF10A, 0x1202], delay_timer=10, sound_timer=5).frames(1)
    assert (c.pc, c.delay_timer, c.sound_timer) == (START, 9, 4)
    c.frames(1, held(3))
    assert (c.pc, c.delay_timer, c.key_wait) == (START, 8, 3)
    c.frames(1, 0)
    assert (c.pc, c.V[1], c.delay_timer) == (0x202, 3, 7)


def test_run_frames_accepts_both_key_forms(chip):
    # 200: skip if key 7 | 202: V2 += 1 | 204: V3 += 1 | 206: loop
    program = [0xE79E, 0x7201, 0x7301, 0x1206]
    by_mask = chip(program, V={7: 7}).frames(1, held(7))
    by_bools = chip(program, V={7: 7}).frames(1, np.arange(16) == 7)
    assert (by_mask.V[2], by_mask.V[3]) == (0, 1)
    assert np.array_equal(by_mask.snapshot()["V"], by_bools.snapshot()["V"])
