"""Control flow: 00EE 1NNN 2NNN 3XNN 4XNN 5XY0 9XY0 BNNN, 12-bit pc wrap, the stack, and the
opcodes that must do nothing but advance pc (docs/machine.md, "anything else").
"""


import numpy as np
import pytest
from chip_builder import NEXT, SKIPPED, START, hexid, quirks

PROFILES = ["chip8", "schip"]


def at(address: int, *words: int) -> dict:
    """A `memory=` entry placing 16-bit words at `address`."""
    return {address: b"".join(w.to_bytes(2, "big") for w in words)}


@pytest.mark.parametrize("profile", PROFILES)
def test_1nnn_jumps(chip, profile):
    assert chip([0x1ABC], profile).step().pc == 0xABC
    assert chip([0x1200], profile).step(times=3).pc == START


@pytest.mark.parametrize("profile", PROFILES)
def test_2nnn_calls_and_00ee_returns(chip, profile):
    c = chip([0x2ABC], profile).step()
    assert (c.pc, c.sp, c.stack[0]) == (0xABC, 1, NEXT)
    c = chip([0x2206, 0x1202, 0x0000, 0x00EE], profile).step()
    assert (c.pc, c.sp) == (0x206, 1)
    c.step()
    assert (c.pc, c.sp) == (NEXT, 0)


def test_nested_calls_return_in_order(chip):
    # 200: call 206 | 202: loop | 204: ret | 206: call 204 | 208: ret
    c = chip([0x2206, 0x1202, 0x00EE, 0x2204, 0x00EE])
    trail = [(c.step().pc, c.sp) for _ in range(4)]
    assert trail == [(0x206, 1), (0x204, 2), (0x208, 1), (0x202, 0)]
    assert list(c.stack[:2]) == [0x202, 0x208]


def test_stack_pointer_wraps_on_call(chip):
    c = chip([0x2ABC], sp=15).step()
    assert (c.pc, c.sp, c.stack[15]) == (0xABC, 0, NEXT)


def test_stack_pointer_wraps_on_return(chip):
    stack = [0] * 16
    stack[15] = 0x345
    c = chip([0x00EE], sp=0, stack=stack).step()
    assert (c.pc, c.sp) == (0x345, 15)


def test_seventeenth_nested_call_overwrites_the_first(chip):
    # 0x200 + 2k calls 0x202 + 2k, for k = 0..16; 0x222 returns.
    calls = [0x2000 | (0x202 + 2 * k) for k in range(17)]
    c = chip(calls + [0x00EE]).step(times=17)
    assert (c.pc, c.sp) == (0x222, 1)
    assert c.stack[0] == 0x222 and c.stack[1] == 0x204  # call 17 (k=16) replaced call 1's return
    c.step()
    assert (c.pc, c.sp) == (0x222, 0)
    c.step()
    assert (c.pc, c.sp) == (0x220, 15)


SKIPS = [  # (opcode, V1, V2, taken)
    (0x3142, 0x42, 0x00, True), (0x3143, 0x42, 0x00, False),
    (0x4142, 0x42, 0x00, False), (0x4143, 0x42, 0x00, True),
    (0x5120, 0x42, 0x42, True), (0x5120, 0x42, 0x24, False),
    (0x9120, 0x42, 0x42, False), (0x9120, 0x42, 0x24, True),
]


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("opcode, v1, v2, taken", SKIPS, ids=hexid)
def test_conditional_skips(chip, profile, opcode, v1, v2, taken):
    c = chip([opcode], profile, V={1: v1, 2: v2, 0xF: 0x55}).step()
    assert c.pc == (SKIPPED if taken else NEXT)
    assert list(c.V[[1, 2, 0xF]]) == [v1, v2, 0x55]


def test_pc_wraps_past_the_end_of_memory(chip):
    c = chip([0x1FFE], memory=at(0xFFE, 0x6A42)).step()
    assert c.pc == 0xFFE
    c.step()
    assert (c.V[0xA], c.pc) == (0x42, 0x000)


def test_fetch_wraps_within_an_instruction(chip):
    c = chip([0x1FFF], memory={0xFFF: [0x6B], 0x000: [0x07]}).step(times=2)
    assert (c.V[0xB], c.pc) == (0x07, 0x001)


def test_skip_wraps_past_the_end_of_memory(chip):
    c = chip([0x1FFE], memory=at(0xFFE, 0x3000)).step(times=2)
    assert c.pc == 0x002


def test_call_from_the_last_word_returns_to_zero(chip):
    c = chip([0x1FFE], memory={**at(0xFFE, 0x2300), **at(0x300, 0x00EE)}).step(times=3)
    assert (c.pc, c.sp) == (0x000, 0)


BNNN = [  # (quirks, opcode, V0, VX (x = high nibble of nnn), target)
    (dict(jump_uses_vx=False), 0xB300, 0x10, 0x20, 0x310),
    (dict(jump_uses_vx=True), 0xB300, 0x10, 0x20, 0x320),
    (dict(jump_uses_vx=False), 0xBFFF, 0x02, 0x50, 0x001),
    (dict(jump_uses_vx=True), 0xBFFF, 0x50, 0x02, 0x001),
    (dict(jump_uses_vx=True), 0xB0F0, 0x20, 0x20, 0x110),  # x = 0: VX is V0
]


@pytest.mark.parametrize("quirk, opcode, v0, vx, target", BNNN, ids=hexid)
def test_bnnn_jumps_with_offset(chip, quirk, opcode, v0, vx, target):
    x = (opcode >> 8) & 0xF
    c = chip([opcode], quirks(**quirk), V={x: vx, 0: v0} if x else {0: v0}).step()
    assert c.pc == target


@pytest.mark.parametrize("profile, target", [("chip8", 0x310), ("schip", 0x320)])
def test_bnnn_follows_the_profile(chip, profile, target):
    assert chip([0xB300], profile, V={0: 0x10, 3: 0x20}).step().pc == target


NO_OPS = [
    0x0000, 0x0123, 0x0FFF, 0x00E1, 0x00EF, 0x01E0, 0x00C5, 0x00D5, 0x00FB, 0x00FC, 0x00FD,
    0x00FE, 0x00FF, 0x5121, 0x5122, 0x5123, 0x512F, 0x9121, 0x912F,
    0x8128, 0x8129, 0x812A, 0x812B, 0x812C, 0x812D, 0x812F,
    0xE100, 0xE19F, 0xE1A0, 0xE1A2, 0xE19D, 0xF000, 0xF100, 0xF101, 0xF102, 0xF108,
    0xF13A, 0xF130, 0xF175, 0xF185, 0xF1FF, 0xF10B, 0xF166,
]


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("opcode", NO_OPS, ids=[f"{op:04X}" for op in NO_OPS])
def test_unlisted_opcodes_only_advance_pc(chip, profile, opcode):
    screen = np.zeros((32, 2), np.uint32)
    screen[3] = [0x0F0F0F0F, 0xF0F0F0F0]
    c = chip([opcode], profile, V={x: 0x11 * x for x in range(16)}, I=0x300, sp=3,
             stack=list(range(0x300, 0x310)), delay_timer=9, sound_timer=7, screen=screen)
    before = c.snapshot()
    c.step(keys=0xFFFF)
    after = c.snapshot()
    assert after.pop("pc") == NEXT
    before.pop("pc")
    changed = [name for name in before if not np.array_equal(before[name], after[name])]
    assert not changed, f"{opcode:04X} changed {changed}"
