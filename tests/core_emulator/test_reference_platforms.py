"""SUPER-CHIP and XO-CHIP (issue 12): the reference interpreter by hand, and the Timendus verdicts
on both the reference and the JAX core.

Two kinds of check, neither reading the JAX code: tiny programs whose registers, memory and
screens are worked out by hand from the platform contract (tests/reference.py's docstring), and
the Timendus test suite's own verdicts: 5-quirks in SUPER-CHIP (0x1FF = 2) and XO-CHIP (3) modes,
and 8-scrolling (0x1FF = 1, 3, 4, 5), whose arrows must end inside the boxes its source draws.
"""

from __future__ import annotations

import numpy as np
import pytest
import screen_text as st
from reference import BIG_FONT, BIG_FONT_ADDRESS, PROFILES, RefMachine, assemble
from screen_text import FLAG_ERR, FLAG_OK

START = 0x200


def machine(*words, platform="schip", quirks=None, data=b""):
    return RefMachine(assemble(*words) + data, quirks or platform, platform=platform)


def steps(m, count):
    for _ in range(count):
        m.execute(0)
    return m


def lit(m, plane=0):
    """The lit (x, y) cells of a plane of the 128x64 grid."""
    return {(x, y) for y, row in enumerate(m.planes[plane]) for x, on in enumerate(row) if on}


def block(x, y, w, h):
    return {(i, j) for i in range(x, x + w) for j in range(y, y + h)}


# --------------------------------------------------------------------------- SUPER-CHIP by hand


def test_boot_has_both_fonts_and_a_lores_screen():
    snap = machine(0x1200).snapshot()
    assert bytes(snap["memory"][BIG_FONT_ADDRESS:BIG_FONT_ADDRESS + 160]) == BIG_FONT
    assert snap["screen"].shape == (64, 128) and not snap["hires"] and not snap["exited"]
    assert snap["memory"].shape == (4096,) and snap["flags"].shape == (16,)
    assert "plane" not in snap  # XO-CHIP only
    # the big "8" is the 8x10 shape the docstring draws: full, open, full, open, full rows
    assert list(BIG_FONT[80:90]) == [0xFF, 0xFF, 0xC3, 0xC3, 0xFF, 0xFF, 0xC3, 0xC3, 0xFF, 0xFF]


def test_a_lores_pixel_is_a_2x2_block_and_hires_a_single_cell():
    # 6005 6103 A20C D011 (one pixel at lores (5, 3)) 00FF D011 (hires: one cell at (5, 3)); data 0x80
    lo = steps(machine(0x6005, 0x6103, 0xA20C, 0xD011, 0x1208, 0x0000, 0x8000), 4)
    assert lit(lo) == block(10, 6, 2, 2) and lo.V[0xF] == 0
    hi = steps(machine(0x6005, 0x6103, 0xA20E, 0x00FF, 0xD011, 0x120A, 0x0000, 0x8000), 5)
    assert hi.hires and lit(hi) == {(5, 3)}


def test_mode_switches_clear_the_screen():
    m = steps(machine(0xA20A, 0xD001, 0x00FF, 0xD001, 0x00FE, 0x8000), 2)
    assert lit(m) == block(0, 0, 2, 2)
    steps(m, 1)
    assert m.hires and lit(m) == set()
    steps(m, 2)
    assert not m.hires and lit(m) == set()


def test_dxy0_draws_16x16_from_32_bytes_and_reports_collision():
    sprite = bytes([0xFF, 0xFF] * 16)
    m = machine(0x00FF, 0xA20A, 0xD000, 0xD000, 0x1208, data=sprite)
    steps(m, 3)
    assert lit(m) == block(0, 0, 16, 16) and m.V[0xF] == 0
    steps(m, 1)
    assert lit(m) == set() and m.V[0xF] == 1
    lores = steps(machine(0xA204, 0xD000, data=sprite), 2)
    assert lit(lores) == block(0, 0, 32, 32)  # 16x16 lores pixels


def test_clipping_and_wrapping_at_the_hires_edges():
    words = (0x00FF, 0x607C, 0x613F, 0xA20C, 0xD012, 0x120A, 0xFFFF)  # 8x2 at (124, 63)
    clipped = steps(machine(*words), 5)
    assert lit(clipped) == block(124, 63, 4, 1)
    wrapped = steps(machine(*words, quirks=PROFILES["xochip"]), 5)
    assert lit(wrapped) == block(124, 63, 4, 1) | block(0, 63, 4, 1) | block(124, 0, 4, 1) | block(0, 0, 4, 1)


@pytest.mark.parametrize("hires, scale", [(True, 1), (False, 2)])
def test_scrolls_move_by_screen_pixels(hires, scale):
    prefix = (0x00FF,) if hires else (0x00FE,)
    # one pixel at screen (8, 8), then scroll down 3, right 4, left 4, left 4
    m = machine(*prefix, 0x6008, 0xA20E, 0xD001, 0x00C3, 0x00FB, 0x1212, 0x8000)
    steps(m, 6)
    assert lit(m) == block(12 * scale, 11 * scale, scale, scale)
    m = machine(*prefix, 0x6008, 0xA210, 0xD001, 0x00C3, 0x00FC, 0x00FC, 0x1214, 0x8000)
    steps(m, 7)
    assert lit(m) == block(0, 11 * scale, scale, scale)


def test_scrolled_out_pixels_are_gone():
    m = steps(machine(0x00FF, 0x607F, 0xA20C, 0xD001, 0x00FB, 0x120A, 0x8000), 5)
    assert lit(m) == set()


def test_big_digit_flags_and_exit():
    m = machine(0x6A0C, 0xFA30, 0x6007, 0x6109, 0xF175, 0x6000, 0x6100, 0xF185, 0x00FD, 0x6042)
    steps(m, 2)
    assert m.I == BIG_FONT_ADDRESS + 10 * 0xC
    steps(m, 3)
    assert m.flags[:3] == [7, 9, 0]
    steps(m, 3)
    assert m.V[:2] == [7, 9]
    m.delay_timer = 5
    m.run_frame(0)
    assert m.exited and m.pc == START + 16 and m.V[0] == 7 and m.delay_timer == 4  # its own frame ticks
    before = m.snapshot()
    for _ in range(3):
        m.run_frame(0)
    after = m.snapshot()
    assert all(np.array_equal(before[k], after[k]) for k in before)  # nothing moves after the exit


def test_the_chip8_platform_has_none_of_them():
    m = machine(0x00FF, 0x00C3, 0x00FB, 0x00FD, 0x6A01, 0xFA30, 0xFA75, platform="chip8", quirks="chip8")
    steps(m, 7)
    assert m.pc == START + 14 and m.I == 0 and m.screen == [[False] * 64 for _ in range(32)]
    assert "hires" not in m.snapshot()


# --------------------------------------------------------------------------- XO-CHIP by hand


def xo(*words, data=b""):
    return machine(*words, platform="xochip", data=data)


def test_long_i_and_skips_over_it():
    m = steps(xo(0xF000, 0xBEEF), 1)
    assert m.I == 0xBEEF and m.pc == START + 4
    m = steps(xo(0x3000, 0xF000, 0x1234, 0x6001), 2)  # V0 == 0: skip the whole 4-byte F000
    assert m.pc == START + 8 and m.V[0] == 1 and m.I == 0
    m = steps(xo(0x3001, 0xF000, 0x1234), 2)  # no skip: F000 runs
    assert m.I == 0x1234


def test_register_ranges_in_both_orders_leave_i():
    m = xo(0x6001, 0x6102, 0x6203, 0xA300, 0x5022, 0xA310, 0x5202, 0xA300, 0x5423)
    steps(m, 7)
    assert list(m.memory[0x300:0x303]) == [1, 2, 3] and list(m.memory[0x310:0x313]) == [3, 2, 1]
    assert m.I == 0x310
    steps(m, 2)  # load V4..V2 from 0x300: V4 = 1, V3 = 2, V2 = 3
    assert m.V[2:5] == [3, 2, 1] and m.I == 0x300


def test_64k_memory_wraps_and_holds_long_programs():
    m = steps(xo(0xF000, 0xFFFF, 0x6107, 0xF155), 3)  # memory_increment: I moves past the end
    assert m.memory[0xFFFF] == 0 and m.memory[0x0000] == 7 and m.I == 1  # V0, V1
    long = RefMachine(bytes(65536 - 0x200), "xochip", platform="xochip")
    assert long.snapshot()["memory"].shape == (65536,)
    with pytest.raises(AssertionError, match="too large"):
        RefMachine(bytes(65536 - 0x200 + 1), "xochip", platform="xochip")


def test_planes_select_what_drawing_clearing_and_scrolling_touch():
    # plane 3: an 8x1 sprite reads byte 0xF0 for plane 1, then 0x0F for plane 2
    m = xo(0x00FF, 0xF301, 0xA212, 0xD001, 0xF201, 0x00C2, 0xF101, 0x00E0, 0x1210, data=bytes([0xF0, 0x0F]))
    steps(m, 4)
    assert lit(m, 0) == block(0, 0, 4, 1) and lit(m, 1) == block(4, 0, 4, 1)
    steps(m, 2)  # plane 2 alone scrolls down 2
    assert lit(m, 0) == block(0, 0, 4, 1) and lit(m, 1) == block(4, 2, 4, 1)
    steps(m, 2)  # plane 1 alone is cleared
    assert lit(m, 0) == set() and lit(m, 1) == block(4, 2, 4, 1)
    snap = m.snapshot()
    assert snap["screen"].shape == (2, 64, 128) and snap["plane"] == 1


def test_scroll_up_audio_and_pitch():
    # one pixel at (5, 10), scroll up 3; then F002 from I = 0x218 and pitch 0x30
    m = xo(0x00FF, 0x6005, 0x610A, 0xA216, 0xD011, 0x00D3, 0xA218, 0xF002, 0x6A30, 0xFA3A, 0x1214,
           data=bytes([0x80, 0x00]) + bytes(range(0x80, 0x90)))
    steps(m, 5)
    assert lit(m) == {(5, 10)}
    steps(m, 1)
    assert lit(m) == {(5, 7)}
    steps(m, 4)
    assert m.audio_pattern == list(range(0x80, 0x90)) and m.pitch == 0x30


# --------------------------------------------------------------------------- the Timendus suite

class SuiteRun:
    """A Timendus ROM with its mode byte set, on the reference ("reference") or the JAX core
    ("core"): the same verdicts must hold on both."""

    def __init__(self, impl, rom, mode, platform, ipf, jit_run_frames):
        data = (st.SUITE / f"{rom}.ch8").read_bytes()
        self.impl = impl
        if impl == "reference":
            self.ref = RefMachine(data, platform, instructions_per_frame=ipf, platform=platform)
            self.ref.memory[0x1FF] = mode  # the suite's auto-start byte
        else:
            import jax
            import octax_core
            machine = octax_core.Machine(platform, instructions_per_frame=ipf)
            self.state = octax_core.poke(machine.boot(data, jax.random.key(0)), 0x1FF, bytes([mode]))
            # one frame a call: the program of a platform's every mode and ROM here, and of
            # test_random_programs_platforms.py's frame property (same machine): one compile
            self.run = jit_run_frames(machine)

    def frames(self, count):
        if self.impl == "reference":
            self.ref.run_frames(0, count)
        else:
            for _ in range(count):
                self.state = self.run(self.state, 0, 1)

    def screen(self):
        """Plane 1's visible screen in screen pixels: 64x32 in lores (each a uniform 2x2 block)."""
        if self.impl == "reference":
            grid, hires = np.array(self.ref.planes[0], dtype=bool), self.ref.hires
        else:
            import octax_core
            snap = octax_core.snapshot(self.state)
            grid, hires = snap["screen"].reshape(-1, 64, 128)[0], bool(snap["hires"])
        if hires:
            return grid
        assert (grid[::2, ::2] == grid[1::2, ::2]).all() and (grid[::2, ::2] == grid[::2, 1::2]).all()
        return grid[::2, ::2]


IMPLEMENTATIONS = ("reference", "core")
# Both ROMs at the random-program tests' speed (their machines and frame program are these), in
# 1-frame calls: the 5-quirks verdicts settle within 300 frames, the arrows within 60.
IPF = 11


@pytest.mark.shared
@pytest.mark.parametrize("impl", IMPLEMENTATIONS)
@pytest.mark.parametrize("mode, platform", [(2, "schip"), (3, "xochip")])
def test_quirks_rom_passes_every_quirk(mode, platform, impl, jit_run_frames):
    run = SuiteRun(impl, "5-quirks", mode, platform, IPF, jit_run_frames)
    for _ in range(15 * 6):
        run.frames(10)
        if st.mark_at(run.screen(), 59, 27, FLAG_OK, FLAG_ERR) != "missing":
            break
    screen = run.screen()
    marks = [st.mark_at(screen, 59, y + 1, FLAG_OK, FLAG_ERR) for _, _, y in st.QUIRK_ROWS]
    assert marks == ["ok"] * 6, st.to_text(screen)


# 8-scrolling.8o: per mode, the border lines its last loops draw, as (x0, x1, y) rows and
# (x, y0, y1) columns, inclusive; the arrows drawn before them must end inside those boxes.
SCROLL_BORDERS = {
    1: ([(21, 30, 26), (33, 42, 26), (21, 30, 15), (33, 42, 15), (27, 36, 4)],
        [(20, 16, 25), (31, 16, 25), (32, 16, 25), (43, 16, 25), (26, 5, 14), (37, 5, 14)]),
    3: ([(53, 62, 43), (65, 74, 43), (53, 62, 32), (65, 74, 32), (59, 68, 21)],
        [(52, 33, 42), (63, 33, 42), (64, 33, 42), (75, 33, 42), (58, 22, 31), (69, 22, 31)]),
    4: ([(21, 41, 26), (21, 41, 15), (21, 41, 4)], [(20, 5, 25), (31, 5, 25), (42, 5, 25)]),
    5: ([(53, 73, 21), (53, 73, 32), (53, 73, 43)], [(52, 22, 42), (63, 22, 42), (74, 22, 42)]),
}
SCROLL_BOXES = {  # the insides of those boxes, (x0, y0, x1, y1) inclusive
    1: [(21, 16, 30, 25), (33, 16, 42, 25), (27, 5, 36, 14)],
    3: [(53, 33, 62, 42), (65, 33, 74, 42), (59, 22, 68, 31)],
    4: [(21, 5, 30, 14), (32, 5, 41, 14), (21, 16, 30, 25), (32, 16, 41, 25)],
    5: [(53, 22, 62, 31), (64, 22, 73, 31), (53, 33, 62, 42), (64, 33, 73, 42)],
}
SCROLL_ARROWS = {1: ("left", "right", "down"), 3: ("left", "right", "down"),
                 4: ("left", "right", "up", "down"), 5: ("left", "right", "up", "down")}


def border_pixels(mode):
    """The border as the ROM XOR-draws it (a pixel drawn twice is dark)."""
    count = {}
    rows, columns = SCROLL_BORDERS[mode]
    for x0, x1, y in rows:
        for x in range(x0, x1 + 1):
            count[(x, y)] = count.get((x, y), 0) + 1
    for x, y0, y1 in columns:
        for y in range(y0, y1 + 1):
            count[(x, y)] = count.get((x, y), 0) + 1
    return {p for p, c in count.items() if c % 2}


@pytest.mark.shared
@pytest.mark.parametrize("impl", IMPLEMENTATIONS)
@pytest.mark.parametrize("mode, platform", [(1, "schip"), (3, "schip"), (4, "xochip"), (5, "xochip")])
def test_scrolling_rom_puts_every_arrow_in_a_box(mode, platform, impl, jit_run_frames):
    source = (st.SUITE / "8-scrolling.8o").read_text()
    run = SuiteRun(impl, "8-scrolling", mode, platform, IPF, jit_run_frames)
    run.frames(120)
    screen = run.screen()
    on = {(x, y) for y, x in zip(*np.nonzero(screen))}
    border = border_pixels(mode)
    assert border <= on, st.to_text(screen)
    arrows = on - border
    found = []
    for name in SCROLL_ARROWS[mode]:
        sprite = st.sprite_bits(st.octo_bytes(source, f"scrolling-arrow-{name}"))
        hits = [(x, y) for x in range(screen.shape[1] - 7) for y in range(screen.shape[0] - 7)
                if {(x + i, y + j) for j, i in zip(*np.nonzero(sprite))} <= arrows
                and not screen[y:y + 8, x:x + 8][~sprite].any()]
        assert len(hits) == 1, (name, hits, st.to_text(screen))
        found.append(hits[0])
    boxes = [next((b for b in SCROLL_BOXES[mode] if b[0] <= x and x + 7 <= b[2] and b[1] <= y and y + 7 <= b[3]), None)
             for x, y in found]
    assert None not in boxes and len(set(boxes)) == len(boxes), (found, st.to_text(screen))
    arrow_bits = sum(int(st.sprite_bits(st.octo_bytes(source, f"scrolling-arrow-{n}")).sum()) for n in SCROLL_ARROWS[mode])
    assert arrow_bits == len(arrows), st.to_text(screen)  # nothing else is lit
