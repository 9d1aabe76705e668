"""Memory opcodes: ANNN FX1E FX29 FX33 FX55 FX65, the boot image, and 12-bit wraps of I."""


import numpy as np
import pytest
from chip_builder import NEXT, START, hexid, quirks

# The common 4x5 hex font (docs/machine.md: at 0x50..0x9F).
FONT = bytes.fromhex(
    "F0909090F0" "2060202070" "F010F080F0" "F010F010F0" "9090F01010" "F080F010F0" "F080F090F0" "F010204040"
    "F090F090F0" "F090F010F0" "F090F09090" "E090E090E0" "F0808080F0" "E0909090E0" "F080F080F0" "F080F08080"
)


def test_boot_image(chip):
    program = [0x1234, 0xABCD, 0x00E0]
    c = chip(program)
    memory = c.memory
    assert memory.shape == (4096,) and memory.dtype == np.uint8
    assert bytes(memory[0x50:0xA0]) == FONT
    assert bytes(memory[0x200:0x206]) == bytes.fromhex("1234ABCD00E0")
    assert not memory[:0x50].any() and not memory[0xA0:0x200].any() and not memory[0x206:].any()
    assert (c.pc, c.I, c.sp, c.delay_timer, c.sound_timer, c.key_wait) == (START, 0, 0, 0, 0, 0xFF)
    assert not c.V.any() and not c.stack.any() and not c.screen.any()


def test_snapshot_dtypes(chip):
    snap = chip([0x1200]).snapshot()
    expected = dict(memory=((4096,), np.uint8), V=((16,), np.uint8), I=((), np.uint16), pc=((), np.uint16),
                    sp=((), np.uint8), stack=((16,), np.uint16), delay_timer=((), np.uint8),
                    sound_timer=((), np.uint8), screen=((32, 64), np.bool_), rng=((), np.uint32),
                    key_wait=((), np.uint8))
    assert {k: (v.shape, v.dtype) for k, v in snap.items()} == expected


@pytest.mark.parametrize("nnn", [0x000, 0x123, 0xFFF], ids=hexid)
def test_annn(chip, nnn):
    c = chip([0xA000 | nnn]).step()
    assert (c.I, c.pc) == (nnn, NEXT)


@pytest.mark.parametrize("profile", ["chip8", "schip"])
@pytest.mark.parametrize(
    "i, vx, result", [(0x100, 0x20, 0x120), (0xFFF, 0x02, 0x001), (0xF10, 0xFF, 0x00F), (0xFFF, 0x00, 0xFFF)],
    ids=hexid,
)
def test_fx1e_adds_to_i_and_wraps_without_flag(chip, profile, i, vx, result):
    c = chip([0xF11E], profile, I=i, V={1: vx, 0xF: 0x55}).step()
    assert (c.I, c.V[0xF], c.pc) == (result, 0x55, NEXT)


def test_ff1e_uses_vf_and_leaves_it(chip):
    c = chip([0xFF1E], I=0xFFF, V={0xF: 0x10}).step()
    assert (c.I, c.V[0xF]) == (0x00F, 0x10)


FONT_DIGITS = [(d, 0x50 + 5 * d) for d in range(16)] + [(0x1A, 0x82), (0xFF, 0x9B)]


@pytest.mark.parametrize("vx, address", FONT_DIGITS, ids=hexid)
def test_fx29_points_i_at_the_font_digit(chip, vx, address):
    c = chip([0xF129], V={1: vx}).step()
    assert (c.I, c.pc) == (address, NEXT)
    assert bytes(c.memory[c.I : c.I + 5]) == FONT[5 * (vx & 0xF) : 5 * (vx & 0xF) + 5]


@pytest.mark.parametrize("profile", ["chip8", "schip"])
@pytest.mark.parametrize(
    "vx, digits",
    [(137, (1, 3, 7)), (65, (0, 6, 5)), (4, (0, 0, 4)), (255, (2, 5, 5)), (0, (0, 0, 0)), (100, (1, 0, 0))],
    ids=hexid,
)
def test_fx33_bcd(chip, profile, vx, digits):
    c = chip([0xF133], profile, I=0x300, V={1: vx}, memory={0x2FF: [0xEE] * 5}).step()
    assert tuple(c.memory[0x300:0x303]) == digits
    assert (c.memory[0x2FF], c.memory[0x303], c.I, c.pc) == (0xEE, 0xEE, 0x300, NEXT)


def test_fx33_wraps(chip):
    c = chip([0xF133], I=0xFFE, V={1: 123}, memory={0xFFD: [0xEE], 0x001: [0xEE]}).step()
    assert list(c.memory[[0xFFD, 0xFFE, 0xFFF, 0x000, 0x001]]) == [0xEE, 1, 2, 3, 0xEE]


@pytest.mark.parametrize("increment", [False, True])
@pytest.mark.parametrize("x", [0x0, 0x3, 0xF])
def test_fx55_stores_v0_to_vx(chip, increment, x):
    regs = {r: 0x10 + r for r in range(16)}
    c = chip([0xF055 | x << 8], quirks(memory_increment=increment), I=0x300, V=regs,
             memory={0x2FF: [0xEE] * 18}).step()
    assert list(c.memory[0x300 : 0x301 + x]) == [0x10 + r for r in range(x + 1)]
    assert (c.memory[0x2FF:0x311] == 0xEE).sum() == 18 - (x + 1)  # nothing else written
    assert (c.I, c.pc) == ((0x301 + x) if increment else 0x300, NEXT)
    assert list(c.V) == [0x10 + r for r in range(16)]


@pytest.mark.parametrize("increment", [False, True])
@pytest.mark.parametrize("x", [0x0, 0x3, 0xF])
def test_fx65_loads_v0_to_vx(chip, increment, x):
    c = chip([0xF065 | x << 8], quirks(memory_increment=increment), I=0x300, V={r: 0xEE for r in range(16)},
             memory={0x300: [0x20 + k for k in range(16)]}).step()
    assert list(c.V) == [0x20 + r if r <= x else 0xEE for r in range(16)]
    assert (c.I, c.pc) == ((0x301 + x) if increment else 0x300, NEXT)


@pytest.mark.parametrize("profile, increment", [("chip8", True), ("schip", False)])
def test_memory_increment_follows_the_profile(chip, profile, increment):
    assert chip([0xF255], profile, I=0x300).step().I == (0x303 if increment else 0x300)


@pytest.mark.parametrize("increment", [False, True])
def test_fx55_wraps_at_the_end_of_memory(chip, increment):
    c = chip([0xF355], quirks(memory_increment=increment), I=0xFFE, V={0: 0xA0, 1: 0xA1, 2: 0xA2, 3: 0xA3},
             memory={0xFFD: [0xEE], 0x002: [0xEE]}).step()
    assert list(c.memory[[0xFFD, 0xFFE, 0xFFF, 0x000, 0x001, 0x002]]) == [0xEE, 0xA0, 0xA1, 0xA2, 0xA3, 0xEE]
    assert c.I == (0x002 if increment else 0xFFE)


@pytest.mark.parametrize("increment", [False, True])
def test_fx65_wraps_at_the_end_of_memory(chip, increment):
    c = chip([0xF365], quirks(memory_increment=increment), I=0xFFE,
             memory={0xFFE: [0xB0, 0xB1], 0x000: [0xB2, 0xB3]}).step()
    assert list(c.V[:5]) == [0xB0, 0xB1, 0xB2, 0xB3, 0x00]
    assert c.I == (0x002 if increment else 0xFFE)


def test_memory_increment_wraps_i(chip):
    c = chip([0xFF55], quirks(memory_increment=True), I=0xFF0).step()
    assert c.I == 0x000


def test_fx55_then_fx65_round_trip_with_vf(chip):
    regs = {r: 0x30 + r for r in range(16)}
    c = chip([0xFF55, 0x6F00, 0xFF65], "schip", I=0x400, V=regs).step(times=3)
    assert list(c.V) == [0x30 + r for r in range(16)]


def test_program_can_overwrite_itself(chip):
    # 200: I = 0x206 | 202: V0 = 0x6A; save V0 at 0x206 -> the word at 0x206 becomes 6A?? = "VA := ??"
    c = chip([0xA206, 0x606A, 0xF055, 0x0042], quirks()).step(times=4)
    assert (c.V[0xA], c.pc) == (0x42, 0x208)
