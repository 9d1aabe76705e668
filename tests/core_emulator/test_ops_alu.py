"""ALU opcodes: 6XNN 7XNN 8XY0-8XYE CXNN, with hand-computed results from docs/machine.md.

Flags are written after the result, so with x == F the flag is what VF holds afterwards.
"""


import jax
import pytest
from chip_builder import NEXT, hexid, quirks

import octax_core

PROFILES = ["chip8", "schip"]
VF_BEFORE = 0x55  # a VF value that no tested flag equals


@pytest.mark.parametrize("profile", PROFILES)
def test_6xnn_loads(chip, profile):
    c = chip([0x61AB], profile, V={0xF: VF_BEFORE}).step()
    assert (c.V[1], c.V[0xF], c.pc) == (0xAB, VF_BEFORE, NEXT)
    assert chip([0x6F07], profile).step().V[0xF] == 0x07


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize(
    "vx, nn, result", [(0x10, 0x05, 0x15), (0xFF, 0x01, 0x00), (0x80, 0xFF, 0x7F), (0, 0, 0)],
    ids=hexid,
)
def test_7xnn_adds_without_flag(chip, profile, vx, nn, result):
    c = chip([0x7100 | nn], profile, V={1: vx, 0xF: VF_BEFORE}).step()
    assert (c.V[1], c.V[0xF], c.pc) == (result, VF_BEFORE, NEXT)


def test_7fnn_leaves_no_carry_in_vf(chip):
    assert chip([0x7F01], V={0xF: 0xFF}).step().V[0xF] == 0x00


@pytest.mark.parametrize("vf_reset", [False, True])
def test_8xy0_copies_and_never_resets_vf(chip, vf_reset):
    c = chip([0x8120], quirks(vf_reset=vf_reset), V={1: 0x11, 2: 0x22, 0xF: VF_BEFORE}).step()
    assert (c.V[1], c.V[2], c.V[0xF], c.pc) == (0x22, 0x22, VF_BEFORE, NEXT)


LOGIC = [(0x1, 0xCA | 0xA6), (0x2, 0xCA & 0xA6), (0x3, 0xCA ^ 0xA6)]  # 0xEE, 0x82, 0x6C


@pytest.mark.parametrize("vf_reset", [False, True])
@pytest.mark.parametrize("n, result", LOGIC, ids=["OR", "AND", "XOR"])
def test_8xy1_2_3_logic_and_vf_reset(chip, vf_reset, n, result):
    c = chip([0x8120 | n], quirks(vf_reset=vf_reset), V={1: 0xCA, 2: 0xA6, 0xF: VF_BEFORE}).step()
    assert (c.V[1], c.V[2], c.pc) == (result, 0xA6, NEXT)
    assert c.V[0xF] == (0 if vf_reset else VF_BEFORE)


@pytest.mark.parametrize("vf_reset", [False, True])
@pytest.mark.parametrize("n, result", [(0x1, 0x3C), (0x2, 0x00), (0x3, 0x3C)], ids=["OR", "AND", "XOR"])
def test_8fy1_2_3_reset_comes_after_the_result(chip, vf_reset, n, result):
    c = chip([0x8F20 | n], quirks(vf_reset=vf_reset), V={0xF: 0x0C, 2: 0x30}).step()
    assert c.V[0xF] == (0 if vf_reset else result)


@pytest.mark.parametrize("vf_reset", [False, True])
def test_8xf1_reads_vf_before_resetting_it(chip, vf_reset):
    c = chip([0x81F1], quirks(vf_reset=vf_reset), V={1: 0x0C, 0xF: 0x30}).step()
    assert c.V[1] == 0x3C
    assert c.V[0xF] == (0 if vf_reset else 0x30)


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize(
    "vx, vy, result, carry",
    [(0x10, 0x20, 0x30, 0), (0xF0, 0x0F, 0xFF, 0), (0xFF, 0x01, 0x00, 1), (0x80, 0x80, 0x00, 1),
     (0xFF, 0xFF, 0xFE, 1), (0x00, 0x00, 0x00, 0)],
    ids=hexid,
)
def test_8xy4_add_with_carry(chip, profile, vx, vy, result, carry):
    c = chip([0x8124], profile, V={1: vx, 2: vy, 0xF: VF_BEFORE}).step()
    assert (c.V[1], c.V[2], c.V[0xF], c.pc) == (result, vy, carry, NEXT)


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize(
    "vx, vy, result, no_borrow",
    [(0x30, 0x10, 0x20, 1), (0x10, 0x10, 0x00, 1), (0x10, 0x30, 0xE0, 0), (0x00, 0x01, 0xFF, 0),
     (0xFF, 0x00, 0xFF, 1)],
    ids=hexid,
)
def test_8xy5_sub(chip, profile, vx, vy, result, no_borrow):
    c = chip([0x8125], profile, V={1: vx, 2: vy, 0xF: VF_BEFORE}).step()
    assert (c.V[1], c.V[2], c.V[0xF], c.pc) == (result, vy, no_borrow, NEXT)


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize(
    "vx, vy, result, no_borrow",
    [(0x10, 0x30, 0x20, 1), (0x10, 0x10, 0x00, 1), (0x30, 0x10, 0xE0, 0), (0x01, 0x00, 0xFF, 0),
     (0x00, 0xFF, 0xFF, 1)],
    ids=hexid,
)
def test_8xy7_subn(chip, profile, vx, vy, result, no_borrow):
    c = chip([0x8127], profile, V={1: vx, 2: vy, 0xF: VF_BEFORE}).step()
    assert (c.V[1], c.V[2], c.V[0xF], c.pc) == (result, vy, no_borrow, NEXT)


# (shift_uses_vy, vx, vy, result, flag): the source is VY with the quirk, VX without.
SHR = [
    (True, 0xFF, 0x03, 0x01, 1), (True, 0x00, 0x04, 0x02, 0), (True, 0x01, 0x80, 0x40, 0),
    (False, 0x03, 0xFF, 0x01, 1), (False, 0x04, 0x00, 0x02, 0), (False, 0x01, 0x80, 0x00, 1),
]
SHL = [
    (True, 0x00, 0x81, 0x02, 1), (True, 0xFF, 0x41, 0x82, 0), (True, 0x80, 0x01, 0x02, 0),
    (False, 0x81, 0x00, 0x02, 1), (False, 0x41, 0xFF, 0x82, 0), (False, 0x80, 0x01, 0x00, 1),
]


@pytest.mark.parametrize("uses_vy, vx, vy, result, flag", SHR, ids=hexid)
def test_8xy6_shift_right(chip, uses_vy, vx, vy, result, flag):
    c = chip([0x8126], quirks(shift_uses_vy=uses_vy), V={1: vx, 2: vy, 0xF: VF_BEFORE}).step()
    assert (c.V[1], c.V[2], c.V[0xF], c.pc) == (result, vy, flag, NEXT)


@pytest.mark.parametrize("uses_vy, vx, vy, result, flag", SHL, ids=hexid)
def test_8xye_shift_left(chip, uses_vy, vx, vy, result, flag):
    c = chip([0x812E], quirks(shift_uses_vy=uses_vy), V={1: vx, 2: vy, 0xF: VF_BEFORE}).step()
    assert (c.V[1], c.V[2], c.V[0xF], c.pc) == (result, vy, flag, NEXT)


@pytest.mark.parametrize("profile, uses_vy", [("chip8", True), ("schip", False)])
def test_shift_source_follows_the_profile(chip, profile, uses_vy):
    c = chip([0x8126], profile, V={1: 0x04, 2: 0x10}).step()
    assert c.V[1] == (0x08 if uses_vy else 0x02)


# x == F: the flag overwrites the result. (opcode, VF before, V2, VF after)
FLAG_LAST = [
    (0x8F24, 0xFF, 0x01, 1), (0x8F24, 0x10, 0x20, 0),  # sum 0x00 / 0x30 lost
    (0x8F25, 0x30, 0x10, 1), (0x8F25, 0x10, 0x30, 0),  # difference 0x20 / 0xE0 lost
    (0x8F27, 0x10, 0x30, 1), (0x8F27, 0x30, 0x10, 0),  # difference 0x20 / 0xE0 lost
]


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("opcode, vf, v2, flag", FLAG_LAST, ids=hexid)
def test_flag_written_after_result_when_x_is_f(chip, profile, opcode, vf, v2, flag):
    c = chip([opcode], profile, V={0xF: vf, 2: v2}).step()
    assert (c.V[0xF], c.V[2], c.pc) == (flag, v2, NEXT)


@pytest.mark.parametrize("uses_vy", [False, True])
@pytest.mark.parametrize(
    "opcode, source, flag",
    [(0x8F26, 0x03, 1), (0x8F26, 0x04, 0), (0x8F2E, 0x81, 1), (0x8F2E, 0x41, 0)],
    ids=hexid,
)
def test_shift_flag_written_after_result_when_x_is_f(chip, uses_vy, opcode, source, flag):
    # The shifted value comes from V2 with shift_uses_vy, else from VF itself.
    regs = {2: source, 0xF: 0xF0} if uses_vy else {2: 0xF0, 0xF: source}
    c = chip([opcode], quirks(shift_uses_vy=uses_vy), V=regs).step()
    assert c.V[0xF] == flag


# y == F: VF is read as an operand before the flag replaces it. (opcode, V1, VF, V1 after, VF after)
VF_OPERAND = [
    (0x81F4, 0x10, 0x20, 0x30, 0), (0x81F4, 0xF0, 0x20, 0x10, 1),
    (0x81F5, 0x30, 0x10, 0x20, 1), (0x81F7, 0x10, 0x30, 0x20, 1),
]


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("opcode, v1, vf, result, flag", VF_OPERAND, ids=hexid)
def test_vf_as_operand(chip, profile, opcode, v1, vf, result, flag):
    c = chip([opcode], profile, V={1: v1, 0xF: vf}).step()
    assert (c.V[1], c.V[0xF]) == (result, flag)


@pytest.mark.parametrize("opcode, result, flag", [(0x81F6, 0x02, 1), (0x81FE, 0x0A, 0)], ids=hexid)
def test_shift_of_vf_into_vx(chip, opcode, result, flag):
    c = chip([opcode], quirks(shift_uses_vy=True), V={1: 0xAA, 0xF: 0x05}).step()
    assert (c.V[1], c.V[0xF]) == (result, flag)


@pytest.mark.parametrize(
    "opcode, result, flag", [(0x8114, 0x00, 1), (0x8115, 0x00, 1), (0x8117, 0x00, 1)], ids=hexid
)
def test_same_register_both_sides(chip, opcode, result, flag):
    c = chip([opcode], V={1: 0x80}).step()
    assert (c.V[1], c.V[0xF]) == (result, flag)


def xorshift32(r: int) -> int:
    r ^= (r << 13) & 0xFFFFFFFF
    r ^= r >> 17
    r ^= (r << 5) & 0xFFFFFFFF
    return r


def test_xorshift32_known_answers():
    assert xorshift32(1) == 0x00042021  # 1 ^ 1<<13 = 0x2001; >>17 adds nothing; ^ 0x2001<<5
    assert xorshift32(0x12345678) == 0x87985AA5


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("nn", [0x00, 0xFF, 0x0F, 0xF0, 0x5A], ids=hexid)
def test_cxnn_masks_the_high_byte_of_the_next_rng(chip, profile, nn):
    c = chip([0xC100 | nn, 0xC2FF], profile, rng=0x12345678, V={1: 0x33, 0xF: VF_BEFORE}).step()
    assert (c.V[1], c.rng, c.V[0xF], c.pc) == (0x87 & nn, 0x87985AA5, VF_BEFORE, NEXT)
    c.step()  # the generator advances on each CXNN
    assert (c.V[2], c.rng) == (0x15, 0x155B24A3)


def test_cxnn_into_vf(chip):
    assert chip([0xCFFF], rng=0x12345678).step().V[0xF] == 0x87


def test_boot_seeds_a_nonzero_rng_from_the_key():
    machine = octax_core.Machine("chip8")
    seeds = {int(machine.boot(bytes([0x12, 0x00]), jax.random.key(k)).rng) for k in range(8)}
    assert 0 not in seeds and len(seeds) == 8
    again = int(machine.boot(bytes([0x12, 0x00]), jax.random.key(3)).rng)
    assert again in seeds
