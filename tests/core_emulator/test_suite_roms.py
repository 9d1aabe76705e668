"""The Timendus CHIP-8 test suite (v4.2), judged by what it draws.

Every expectation comes from the ROMs' Octo sources in `shared/roms/test-suite/*.8o`: the
logos are rebuilt from the sprite data and draw coordinates in the source, and the result
marks, characters and their positions are those the source draws. Nothing here compares the
core with an earlier output of itself.

Runs use one static frame count (60 frames, a "second"), so each machine config compiles once.
"""

from __future__ import annotations

import dataclasses
import hashlib
import re

import jax
import numpy as np
import pytest
import screen_text as st
from screen_text import CORAX_NO, CORAX_OK, FLAG_ERR, FLAG_OK

import octax_core

SUITE = st.SUITE
pytestmark = pytest.mark.shared  # the Timendus test suite is only in ../shared
SECOND = 60  # frames
IPF = 11


@pytest.fixture(scope="module")
def run(jit_run_frames, test_suite_dir):
    """run(machine, state, keys=0, seconds=1) -> state, via the session's jitted run_frames, one
    frame a call: the program test_differential.py and the per-opcode tests run on the same
    machines, one compile for all."""
    assert test_suite_dir.resolve() == SUITE.resolve()

    def run(machine, state, keys=0, seconds=1):
        fn = jit_run_frames(machine)
        for _ in range(seconds * SECOND):
            state = fn(state, keys, 1)
        return state

    return run


def machine_for(quirks, ipf=IPF):
    return octax_core.Machine(quirks=quirks, instructions_per_frame=ipf)


def boot(machine, rom: str, mode: int | None = None, patch=None):
    data = (SUITE / f"{rom}.ch8").read_bytes()
    if patch is not None:
        data = patch(data)
    state = machine.boot(data, jax.random.key(0))
    if mode is not None:  # the suite's "auto start" byte, read by the ROM at 0x1FF
        state = octax_core.poke(state, 0x1FF, bytes([mode]))
    return state


def screen_of(state) -> np.ndarray:
    screen = octax_core.snapshot(state)["screen"]
    assert screen.shape == (32, 64) and screen.dtype == bool
    return screen


def run_until(run, machine, state, done, max_seconds, keys=0):
    """Runs whole seconds until done(screen) holds (plus one more second to settle)."""
    for _ in range(max_seconds):
        state = run(machine, state, keys)
        if done(screen_of(state)):
            return run(machine, state, keys)
    raise AssertionError(f"not finished after {max_seconds} s:\n{st.to_text(screen_of(state))}")


def source(rom: str) -> str:
    return (SUITE / f"{rom}.8o").read_text()


# --------------------------------------------------------------------------- files


def test_rom_hashes_match_manifest():
    manifest = dict(
        reversed(line.split()) for line in (SUITE / "SHA1SUMS").read_text().splitlines() if line.strip()
    )
    for rom in ("1-chip8-logo", "2-ibm-logo", "3-corax+", "4-flags", "5-quirks", "6-keypad"):
        for ext in (".ch8", ".8o"):
            name = rom + ext
            assert hashlib.sha1((SUITE / name).read_bytes()).hexdigest() == manifest[name], name


@pytest.mark.parametrize("rom", ["4-flags", "5-quirks", "6-keypad"])
def test_transcribed_glyphs_are_the_roms_own(rom):
    """screen_text's glyph table and marks are the bytes these ROMs carry."""
    data = (SUITE / f"{rom}.ch8").read_bytes()
    assert st.GLYPH_TABLE_BYTES in data
    # flag-ok, then `characters` (one byte), then flag-err, then im0: laid out back to back.
    assert bytes(FLAG_OK[:2]) + bytes([0x80]) + bytes(FLAG_ERR) + bytes(st.GLYPHS["0"]) in data


# --------------------------------------------------------------------------- logos

# (label, x, y) of each `sprite ... 15`, read off 1-chip8-logo.8o: `show X address` with v1 = 1, 16.
CHIP8_LOGO_DRAWS = [(f"splash-{c}-{r}", 8 + 8 * c, (1, 16)[r]) for r in range(2) for c in range(6)]
# 2-ibm-logo.8o: v0 = 12, += 9, 8, 4, 8, 8; v1 = 8.
IBM_LOGO_DRAWS = [
    ("ibm-0-0", 12, 8), ("ibm-1-0", 21, 8), ("ibm-2-0", 29, 8),
    ("ibm-3-0", 33, 8), ("ibm-4-0", 41, 8), ("ibm-5-0", 49, 8),
]


def expected_logo(rom, draws):
    src, data = source(rom), (SUITE / f"{rom}.ch8").read_bytes()
    screen = st.blank()
    for label, x, y in draws:
        rows = st.octo_bytes(src, label)
        assert len(rows) == 15 and rows in data, label  # the source's bytes are the ROM's
        st.blit(screen, rows, x, y)
    return screen


@pytest.mark.parametrize("profile", ["chip8", "schip"])
@pytest.mark.parametrize(
    "rom, draws", [("1-chip8-logo", CHIP8_LOGO_DRAWS), ("2-ibm-logo", IBM_LOGO_DRAWS)]
)
def test_logo(run, profile, rom, draws):
    expected = expected_logo(rom, draws)
    assert expected.sum() > 200  # the parse found the picture
    machine = machine_for(profile)
    screen = screen_of(run(machine, boot(machine, rom)))
    assert np.array_equal(screen, expected), (
        f"got:\n{st.to_text(screen)}\nexpected:\n{st.to_text(expected)}"
    )


# --------------------------------------------------------------------------- 3-corax+

# (name, left image, right image, x2, y), per 3-corax+.8o: four columns x2 = 11, 27, 43, 59,
# rows y = 1, 6, ..., the op label drawn at x2 - 9 and x2 - 5, the result mark at x2.
CORAX_TESTS = [
    ("3XNN", "im3", "imX", 11, 1), ("4XNN", "im4", "imX", 11, 6), ("5XY0", "im5", "imX", 11, 11),
    ("7XNN", "im7", "imX", 11, 16), ("9XY0", "im9", "imX", 11, 21), ("1NNN", "im1", "imX", 11, 26),
    ("2NNN", "im2", "imX", 27, 1), ("00EE", "im0", "imE", 27, 6), ("8XY0", "im8", "im0", 27, 11),
    ("8XY1", "im8", "im1", 27, 16), ("8XY2", "im8", "im2", 27, 21), ("8XY3", "im8", "im3", 27, 26),
    ("8XY4", "im8", "im4", 43, 1), ("8XY5", "im8", "im5", 43, 6), ("8XY7", "im8", "im7", 43, 11),
    ("8XY6", "im8", "im6", 43, 16), ("8XYE", "im8", "imE", 43, 21), ("FX65", "imF", "im6", 43, 26),
    ("FX55", "imF", "im5", 59, 1), ("FX33", "imF", "im3", 59, 6), ("FX1E", "imF", "imE", 59, 11),
    ("8-bit registers", "imV", "imX", 59, 16),
]


@pytest.mark.parametrize("profile", ["chip8", "schip"])
def test_corax_plus_all_pass(run, profile):
    src = source("3-corax+")
    machine = machine_for(profile)
    last_x, last_y = CORAX_TESTS[-1][3:]
    state = run_until(
        run, machine, boot(machine, "3-corax+"),
        lambda s: st.mark_at(s, last_x, last_y, CORAX_OK, CORAX_NO) != "missing", max_seconds=5,
    )
    screen = screen_of(state)
    results = {}
    for name, left, right, x2, y in CORAX_TESTS:
        assert st.matches(screen, st.octo_bytes(src, left), x2 - 9, y), f"{name} label"
        assert st.matches(screen, st.octo_bytes(src, right), x2 - 5, y), f"{name} label"
        results[name] = st.mark_at(screen, x2, y, CORAX_OK, CORAX_NO)
    failed = {name: r for name, r in results.items() if r != "ok"}
    assert not failed, f"{failed}\n{st.to_text(screen)}"
    assert list(results.values()).count("ok") == len(CORAX_TESTS) == 22


# --------------------------------------------------------------------------- 4-flags


def _flags_layout():
    """(name, x, y) of each result mark, following 4-flags.8o's x/y arithmetic.

    `opcode-digit` draws at x, then x += 5; each `flags-draw-result` draws its 3-row mark at
    (x, y + 1), then x += 4. Returns also the (digit, x, y) of each opcode digit.
    """
    rows = [  # (y, [(digit, digit x, result names)])
        (0, [("1", 22, "v2 vF v3"), ("2", 44, "v2 vF v3")]),
        (5, [("3", 0, "v2 vF v3"), ("4", 22, "v2 vF v3 v4"), ("5", 44, "v2 vF v3 v4")]),
        (10, [("6", 0, "v2 vF v3"), ("7", 22, "v2 vF v3 v4"), ("E", 44, "v2 vF v3")]),
        (16, [("4", 22, "v2 vF v3 v4"), ("5", 44, "v2 vF v3 v4")]),
        (21, [("6", 0, "v2 vF v3"), ("7", 22, "v2 vF v3 v4"), ("E", 44, "v2 vF v3")]),
    ]
    marks, digits = [], []
    for y, ops in rows:
        section = "HAPPY" if y < 16 else "CARRY"
        for digit, x, names in ops:
            digits.append((digit, x, y))
            for k, reg in enumerate(names.split()):
                marks.append((f"{section} 8XY{digit} {reg}", x + 5 + 4 * k, y))
    digits += [("F", 22, 27), ("E", 26, 27)]  # OTHER: "FE" = FX1E, x -= 1 between the digits
    marks += [("OTHER FX1E i += v1", 31, 27), ("OTHER FX1E i += vF", 35, 27)]
    return marks, digits


FLAGS_MARKS, FLAGS_DIGITS = _flags_layout()


def flags_results(screen):
    for text, y in (("HAPPY", 0), ("CARRY", 16), ("OTHER", 27)):
        assert st.text_at(screen, 0, y, text), st.to_text(screen)
    for digit, x, y in FLAGS_DIGITS:
        assert st.read_char(screen, x, y) == digit, (digit, x, y)
    return {name: st.mark_at(screen, x, y + 1, FLAG_OK, FLAG_ERR) for name, x, y in FLAGS_MARKS}


def run_flags(run, machine, patch=None):
    x, y = FLAGS_MARKS[-1][1:]
    state = run_until(
        run, machine, boot(machine, "4-flags", patch=patch),
        lambda s: st.mark_at(s, x, y + 1, FLAG_OK, FLAG_ERR) != "missing", max_seconds=5,
    )
    return screen_of(state)


@pytest.mark.parametrize("profile", ["chip8", "schip"])
def test_flags_all_pass(run, profile):
    screen = run_flags(run, machine_for(profile))
    results = flags_results(screen)
    failed = {name: r for name, r in results.items() if r != "ok"}
    assert not failed, f"{failed}\n{st.to_text(screen)}"
    assert list(results.values()).count("ok") == len(FLAGS_MARKS) == 47


def _expect_carry_in_happy_add(rom: bytes) -> bytes:
    """Makes 4-flags expect VF = 1 after the no-overflow 8XY4 (`expect-v2-vf-v3-v4 65 0 35 0`)."""
    # vC := 65; call flags-draw-result; v2 := vE; vC := 0  ->  ... vC := 1
    pattern = re.compile(rb"\x6c\x41([\x20-\x2f].)\x82\xe0\x6c\x00", re.DOTALL)
    assert len(pattern.findall(rom)) == 1
    return pattern.sub(lambda m: b"\x6c\x41" + m.group(1) + b"\x82\xe0\x6c\x01", rom)


def test_flags_check_catches_a_wrong_flag(run):
    """The layout check is sharp: one wrong VF expectation gives exactly one cross, where expected."""
    screen = run_flags(run, machine_for("chip8"), patch=_expect_carry_in_happy_add)
    results = flags_results(screen)
    assert {name: r for name, r in results.items() if r != "ok"} == {"HAPPY 8XY4 vF": "bad"}


# --------------------------------------------------------------------------- 5-quirks

QUIRK_ROWS = st.QUIRK_ROWS
CHIP8_MODE, SCHIP_MODE, XOCHIP_MODE = 1, 2, 3  # 5-quirks.8o `:const CHIP8 1`, `SCHIP_MODERN 2`, `XOCHIP 3`
# What each platform expects the quirk to be (the ROM draws a check when the reading matches).
QUIRK_TARGETS = {
    CHIP8_MODE: dict(vf_reset=True, memory_increment=True, display_wait=True, clipping=True,
                     shift_uses_vy=True, jump_uses_vx=False),
    SCHIP_MODE: dict(vf_reset=False, memory_increment=False, display_wait=False, clipping=True,
                     shift_uses_vy=False, jump_uses_vx=True),
    XOCHIP_MODE: dict(vf_reset=False, memory_increment=True, display_wait=False, clipping=False,
                      shift_uses_vy=True, jump_uses_vx=False),
}


def quirk_reading(mode, field, value):
    """The word 5-quirks prints for a quirk setting.

    SHIFTING reads ON when VX is shifted in place (our shift_uses_vy off). In SUPER-CHIP and XO-CHIP modes
    the ROM measures lores and hires and prints BOTH/NONE; `hires` is a no-op here, so both
    measurements agree.
    """
    if field == "shift_uses_vy":
        value = not value
    if mode in (SCHIP_MODE, XOCHIP_MODE) and field in ("display_wait", "clipping"):
        return "BOTH" if value else "NONE"
    return "ON" if value else "OFF"


QUIRK_WORDS = ("ON", "OFF", "SLOW", "LRES", "HRES", "BOTH", "NONE", "ERR1", "ERR2", "ERR3")  # quirks-on ..


def quirk_word_at(screen, y):
    """The word 5-quirks printed at (42, y): one of its result strings (4 cells, blank-padded)."""
    words = [w for w in QUIRK_WORDS if st.text_at(screen, 42, y, w.ljust(4))]
    return words[0] if words else f"?{st.read_text(screen, 42, y, 4)}"


def run_quirks(run, machine, mode):
    state = run_until(
        run, machine, boot(machine, "5-quirks", mode=mode),
        lambda s: st.mark_at(s, 59, 27, FLAG_OK, FLAG_ERR) != "missing", max_seconds=15,
    )
    screen = screen_of(state)
    got = {}
    for label, field, y in QUIRK_ROWS:
        assert st.text_at(screen, 1, y, label), st.to_text(screen)
        got[field] = (quirk_word_at(screen, y), st.mark_at(screen, 59, y + 1, FLAG_OK, FLAG_ERR))
    return got, screen


@pytest.mark.parametrize("profile, mode", [("chip8", CHIP8_MODE), ("schip", SCHIP_MODE), ("xochip", XOCHIP_MODE)])
def test_quirks_profile_passes(run, profile, mode):
    machine = machine_for(profile)
    assert dataclasses.asdict(machine.quirks) == QUIRK_TARGETS[mode]  # the profile is what the ROM expects
    got, screen = run_quirks(run, machine, mode)
    quirks = machine.quirks
    expected = {f: (quirk_reading(mode, f, getattr(quirks, f)), "ok") for _, f, _ in QUIRK_ROWS}
    assert got == expected, st.to_text(screen)


def test_quirks_reports_a_custom_mix(run):
    """Each line follows the config, not the profile name: every quirk flipped from CHIP-8."""
    flipped = {f: not v for f, v in QUIRK_TARGETS[CHIP8_MODE].items()}
    machine = machine_for(octax_core.Quirks(**flipped))
    got, screen = run_quirks(run, machine, CHIP8_MODE)
    expected = {f: (quirk_reading(CHIP8_MODE, f, v), "bad") for f, v in flipped.items()}
    assert got == expected, st.to_text(screen)


# --------------------------------------------------------------------------- 6-keypad

KEYPAD_DOWN, KEYPAD_UP, KEYPAD_GETKEY = 1, 2, 3  # 6-keypad.8o's 0x1FF values
KEYPAD_ROWS = [("1 2 3 C", 3), ("4 5 6 D", 10), ("7 8 9 E", 17), ("A 0 B F", 24)]  # at x = 18
KEY_BOXES = [  # keypad-coordinates: where key k's 7x6 `keypad-cursor` is XOR-drawn
    (24, 23), (16, 2), (24, 2), (32, 2), (16, 9), (24, 9), (32, 9), (16, 16),
    (24, 16), (32, 16), (16, 23), (32, 23), (40, 2), (40, 9), (40, 16), (40, 23),
]
KEYPAD_CURSOR = [0xFE] * 6


def keypad_labels():
    screen = st.blank()
    for y, (text, _) in zip((3, 10, 17, 24), KEYPAD_ROWS):
        for i, ch in enumerate(text):
            st.blit(screen, st.GLYPHS[ch], 18 + 4 * i, y)
    return screen


def with_boxes(screen, keys):
    screen = screen.copy()
    for k in keys:
        st.blit(screen, KEYPAD_CURSOR, *KEY_BOXES[k])
    return screen


def held(*keys):
    return sum(1 << k for k in keys)


@pytest.fixture(scope="module")
def chip8():
    return machine_for("chip8")


def test_keypad_ex9e_shows_held_keys(run, chip8):
    state = run(chip8, boot(chip8, "6-keypad", mode=KEYPAD_DOWN), seconds=2)
    idle = screen_of(state)
    for text, y in KEYPAD_ROWS:
        assert st.text_at(idle, 18, y, text), st.to_text(idle)
    labels = keypad_labels()
    assert np.array_equal(idle, labels), st.to_text(idle)
    for keys in [(0x0,), (0x5,), (0xA,), (0xF,), (0x1, 0xC)]:
        state = run(chip8, state, held(*keys))
        got = screen_of(state)
        assert np.array_equal(got, with_boxes(labels, keys)), f"keys {keys}:\n{st.to_text(got)}"
        state = run(chip8, state, 0)
        assert np.array_equal(screen_of(state), labels), f"after releasing {keys}"
    # The bool[16] form of the same input.
    state = run(chip8, state, np.arange(16) == 7)
    assert np.array_equal(screen_of(state), with_boxes(labels, [7]))


def test_keypad_exa1_shows_released_keys(run, chip8):
    state = run(chip8, boot(chip8, "6-keypad", mode=KEYPAD_UP), seconds=2)
    labels = keypad_labels()
    all_up = with_boxes(labels, range(16))
    assert np.array_equal(screen_of(state), all_up), st.to_text(screen_of(state))
    state = run(chip8, state, held(0x3, 0x8))
    expected = with_boxes(labels, [k for k in range(16) if k not in (0x3, 0x8)])
    assert np.array_equal(screen_of(state), expected), st.to_text(screen_of(state))
    state = run(chip8, state, 0)
    assert np.array_equal(screen_of(state), all_up)


@pytest.mark.parametrize("profile", ["chip8", "schip"])
def test_keypad_fx0a_waits_for_press_and_release(run, profile):
    machine = machine_for(profile)
    state = run(machine, boot(machine, "6-keypad", mode=KEYPAD_GETKEY), seconds=2)
    waiting = screen_of(state)
    assert st.text_at(waiting, 6, 13, "PRESS ANY KEY"), st.to_text(waiting)
    state = run(machine, state, held(0x9))  # pressed and held: FX0A must not return yet
    assert np.array_equal(screen_of(state), waiting), st.to_text(screen_of(state))
    state = run(machine, state, 0)  # released: "ALL GOOD" with a check at (30, 9)
    screen = screen_of(state)
    assert st.mark_at(screen, 30, 9, FLAG_OK, FLAG_ERR) == "ok", st.to_text(screen)
    assert st.text_at(screen, 16, 17, "ALL GOOD"), st.to_text(screen)
    expected = st.blank()
    st.blit(expected, FLAG_OK, 30, 9)
    for i, ch in enumerate("ALL GOOD"):
        st.blit(expected, st.GLYPHS[ch], 16 + 4 * i, 17)
    assert np.array_equal(screen, expected), st.to_text(screen)


def test_keypad_menu_picks_a_test_by_number(run, chip8):
    state = run(chip8, boot(chip8, "6-keypad"))
    menu = screen_of(state)
    assert st.text_at(menu, 10, 2, "PICK OPCODE"), st.to_text(menu)
    assert st.text_at(menu, 8, 20, "3 FX0A GETKEY"), st.to_text(menu)
    state = run(chip8, state, held(0x3))
    state = run(chip8, state, 0)
    assert st.text_at(screen_of(state), 6, 13, "PRESS ANY KEY"), st.to_text(screen_of(state))
