"""Display opcodes: 00E0 and DXYN (XOR, collision flag, clipping versus wrapping at both edges).

Expected screens are built with `screen_text.blit`, a plain-numpy sprite XOR written from
docs/machine.md, never from the core's output.
"""


import numpy as np
import pytest
import screen_text as st
from chip_builder import NEXT, quirks


def pack(pixels: np.ndarray) -> np.ndarray:
    """(32, 64) bool -> (32, 2) uint32 as MachineState.screen holds it (x = 0 and x = 32 in bit 31)."""
    weights = np.uint64(1) << np.arange(31, -1, -1, dtype=np.uint64)
    words = pixels.reshape(32, 2, 32).astype(np.uint64) @ weights
    return words.astype(np.uint32)


def pattern_screen() -> np.ndarray:
    """A fixed busy background: a checkerboard in the top-left and bottom-right quarters."""
    pixels = st.blank()
    yy, xx = np.mgrid[0:32, 0:64]
    pixels[((xx + yy) % 2 == 0) & (((xx < 32) & (yy < 16)) | ((xx >= 32) & (yy >= 16)))] = True
    return pixels


SPRITE = [0xA5, 0xFF, 0x81, 0x3C]


def test_pack_matches_the_documented_layout():
    pixels = st.blank()
    pixels[0, 0] = pixels[1, 31] = pixels[2, 32] = pixels[3, 63] = True
    assert pack(pixels)[:4].tolist() == [[1 << 31, 0], [1, 0], [0, 1 << 31], [0, 1]]


def test_snapshot_unpacks_row_0_at_the_top(chip):
    pixels = pattern_screen()
    pixels[0, 63] = True
    assert np.array_equal(chip([0x1200], screen=pack(pixels)).screen, pixels)


@pytest.mark.parametrize("profile", ["chip8", "schip"])
def test_00e0_clears(chip, profile):
    c = chip([0x00E0], profile, screen=np.full((32, 2), 0xFFFFFFFF, np.uint32), V={0xF: 0x55}).step()
    assert not c.screen.any()
    assert (c.V[0xF], c.pc) == (0x55, NEXT)


def test_dxyn_draws_a_font_digit(chip):
    c = chip([0xD125], I=0x50, V={1: 10, 2: 5, 0xF: 1}).step()
    expected = st.blank()
    st.blit(expected, bytes.fromhex("F0909090F0"), 10, 5)
    assert np.array_equal(c.screen, expected), st.to_text(c.screen)
    assert (c.V[0xF], c.pc, c.I) == (0, NEXT, 0x50)


def test_dxyn_xor_and_collision(chip):
    memory = {0x300: [0x80, 0x40, 0xC0]}
    # draw 0x80, then 0x40 beside it (no pixel erased), then 0xC0 over both (both erased)
    c = chip([0xA300, 0xD001, 0xA301, 0xD001, 0xA302, 0xD001], memory=memory).step(times=2)
    assert c.V[0xF] == 0 and c.screen[0, :3].tolist() == [True, False, False]
    c.step(times=2)
    assert c.V[0xF] == 0 and c.screen[0, :3].tolist() == [True, True, False]
    c.step(times=2)
    assert c.V[0xF] == 1 and not c.screen.any()


def test_dxyn_partial_collision_sets_flag(chip):
    c = chip([0xD001, 0xA301, 0xD001], I=0x300, memory={0x300: [0xF0, 0x18]}).step(times=3)
    expected = st.blank()
    expected[0, [0, 1, 2, 4]] = True  # F0 ^ 18 = E8
    assert np.array_equal(c.screen, expected)
    assert c.V[0xF] == 1


def test_dxyn_clears_a_stale_flag(chip):
    c = chip([0xD011], I=0x50, V={0xF: 1}).step()
    assert c.V[0xF] == 0


@pytest.mark.parametrize("clipping", [False, True])
def test_dxy0_draws_nothing(chip, clipping):
    background = pattern_screen()
    c = chip([0xD120], quirks(clipping=clipping), I=0x50, V={0xF: 1}, screen=pack(background)).step()
    assert np.array_equal(c.screen, background)
    assert (c.V[0xF], c.pc) == (0, NEXT)


@pytest.mark.parametrize("clipping", [False, True])
@pytest.mark.parametrize("vx, vy", [(70, 40), (64, 32), (255, 255), (127, 63)])
def test_start_position_always_wraps(chip, clipping, vx, vy):
    c = chip([0xD124], quirks(clipping=clipping), I=0x300, V={1: vx, 2: vy}, memory={0x300: SPRITE}).step()
    expected = st.blank()
    st.blit(expected, SPRITE, vx % 64, vy % 32, clip=clipping)
    assert np.array_equal(c.screen, expected), st.to_text(c.screen)


def edge_case(chip, clipping, vx, vy, rows, background=None):
    background = st.blank() if background is None else background
    c = chip([0xD120 | len(rows)], quirks(clipping=clipping), I=0x300, V={1: vx, 2: vy},
             memory={0x300: rows}, screen=pack(background)).step()
    return c


@pytest.mark.parametrize("clipping", [False, True])
def test_right_edge(chip, clipping):
    c = edge_case(chip, clipping, 60, 0, [0xFF])
    lit = sorted(np.flatnonzero(c.screen[0]).tolist())
    assert lit == ([60, 61, 62, 63] if clipping else [0, 1, 2, 3, 60, 61, 62, 63])
    assert c.screen[1:].sum() == 0


@pytest.mark.parametrize("clipping", [False, True])
def test_bottom_edge(chip, clipping):
    c = edge_case(chip, clipping, 0, 30, [0x80] * 4)
    lit = sorted(np.flatnonzero(c.screen[:, 0]).tolist())
    assert lit == ([30, 31] if clipping else [0, 1, 30, 31])
    assert c.screen[:, 1:].sum() == 0


@pytest.mark.parametrize("clipping", [False, True])
def test_bottom_right_corner(chip, clipping):
    c = edge_case(chip, clipping, 62, 31, [0xF0, 0xF0])
    lit = sorted(zip(*np.nonzero(c.screen)))
    corner = [(31, 62), (31, 63)]
    wrapped = [(0, 0), (0, 1), (0, 62), (0, 63), (31, 0), (31, 1)]
    assert lit == sorted(corner if clipping else corner + wrapped)


@pytest.mark.parametrize("clipping, flag", [(False, 1), (True, 0)])
def test_clipped_pixels_do_not_collide(chip, clipping, flag):
    background = st.blank()
    background[0, 0] = background[1, 0] = True  # hit by the wrapped parts only
    c = edge_case(chip, clipping, 60, 31, [0xFF, 0xFF], background)
    assert c.V[0xF] == flag
    assert c.screen[0, 0] == clipping and c.screen[1, 0]


@pytest.mark.parametrize("profile", ["chip8", "schip"])
def test_both_profiles_clip(chip, profile):
    c = chip([0xD121], profile, I=0x300, V={1: 60}, memory={0x300: [0xFF]}).step()
    assert np.flatnonzero(c.screen[0]).tolist() == [60, 61, 62, 63]


@pytest.mark.parametrize("clipping", [False, True])
@pytest.mark.parametrize("vx", [0, 1, 24, 28, 31, 32, 33, 56, 57, 59, 63])
@pytest.mark.parametrize("vy", [0, 13, 28, 31])
def test_dxyn_against_numpy_blit(chip, clipping, vx, vy):
    """Word-boundary and edge positions on a busy background, compared with a plain XOR."""
    background = pattern_screen()
    expected = background.copy()
    flag = st.blit(expected, SPRITE, vx, vy, clip=clipping)
    c = edge_case(chip, clipping, vx, vy, SPRITE, background)
    assert np.array_equal(c.screen, expected), st.to_text(c.screen)
    assert c.V[0xF] == flag


def test_fifteen_rows(chip):
    rows = [0x80 >> (k % 8) for k in range(15)]
    c = chip([0xD12F], I=0x300, V={1: 3, 2: 2}, memory={0x300: rows}).step()
    expected = st.blank()
    st.blit(expected, rows, 3, 2)
    assert np.array_equal(c.screen, expected)


def test_sprite_rows_wrap_around_memory(chip):
    c = chip([0xD002], I=0xFFF, memory={0xFFF: [0x80], 0x000: [0x40]}).step()
    assert sorted(zip(*np.nonzero(c.screen))) == [(0, 0), (1, 1)]


@pytest.mark.parametrize("flag_first", [False, True])
def test_dxyn_with_vf_as_coordinate(chip, flag_first):
    # VF = 5 is the x coordinate; afterwards VF holds the collision flag (0 on a blank screen).
    opcode = 0xDF11 if flag_first else 0xD1F1
    c = chip([opcode, opcode], I=0x300, V={0xF: 5, 1: 2}, memory={0x300: [0x80]}).step()
    assert c.V[0xF] == 0
    expected = (2, 5) if flag_first else (5, 2)  # (row, column)
    assert sorted(zip(*np.nonzero(c.screen))) == [expected]


def test_dxyn_leaves_i_and_memory(chip):
    c = chip([0xD125], I=0x50, V={1: 1, 2: 1})
    memory = c.memory
    c.step()
    assert c.I == 0x50 and np.array_equal(c.memory, memory)
