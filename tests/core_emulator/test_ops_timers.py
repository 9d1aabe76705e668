"""Timer opcodes FX07 FX15 FX18, the 60 Hz tick, instructions per frame and display wait."""


import pytest
from chip_builder import NEXT, SKIPPED, START, quirks


@pytest.mark.parametrize("profile", ["chip8", "schip"])
def test_fx07_reads_the_delay_timer(chip, profile):
    c = chip([0xF107, 0xFF07], profile, delay_timer=0x42, sound_timer=0x17).step()
    assert (c.V[1], c.pc, c.delay_timer) == (0x42, NEXT, 0x42)  # execute alone never ticks
    assert c.step().V[0xF] == 0x42


@pytest.mark.parametrize("profile", ["chip8", "schip"])
def test_fx15_and_fx18_set_the_timers(chip, profile):
    c = chip([0xF115, 0xF218], profile, V={1: 0x33, 2: 0x44}).step(times=2)
    assert (c.delay_timer, c.sound_timer, c.pc) == (0x33, 0x44, SKIPPED)
    assert (c.V[1], c.V[2]) == (0x33, 0x44)


def test_timers_are_independent(chip):
    c = chip([0xF015], V={0: 0}, sound_timer=9).step()
    assert (c.delay_timer, c.sound_timer) == (0, 9)


LOOP = [0x1200]


@pytest.mark.parametrize("profile", ["chip8", "schip"])
@pytest.mark.parametrize(
    "delay, sound, after_1, after_61",
    [(5, 3, (4, 2), (0, 0)), (0, 0, (0, 0), (0, 0)), (100, 255, (99, 254), (39, 194))],
    ids=["small", "zero", "large"],
)
def test_timers_tick_once_per_frame(chip, profile, delay, sound, after_1, after_61):
    c = chip(LOOP, profile, delay_timer=delay, sound_timer=sound).frames(1)
    assert (c.delay_timer, c.sound_timer) == after_1
    c.frames(60)
    assert (c.delay_timer, c.sound_timer) == after_61


def test_tick_comes_after_the_frames_instructions(chip):
    # V0 = 5; delay = V0; V1 = delay; loop  -> V1 sees 5, the frame's tick then leaves 4
    c = chip([0x6005, 0xF015, 0xF107, 0x1206], "schip").frames(1)
    assert (c.V[1], c.delay_timer, c.pc) == (5, 4, 0x206)


@pytest.mark.parametrize("ipf", [1, 11])  # the shortest frame, and the default (each length compiles a program)
def test_instructions_per_frame(chip, ipf):
    c = chip([0x7001] * 40, "schip", ipf=ipf).frames(1)
    assert (c.V[0], c.pc) == (ipf, START + 2 * ipf)
    c.frames(1)
    assert c.V[0] == 2 * ipf


PROGRAM_WITH_DRAWS = [0x7101, 0xD001, 0x7101, 0x7101, 0xD001] + [0x7101] * 20


@pytest.mark.parametrize("profile", ["chip8", None])
def test_display_wait_ends_the_frame_after_dxyn(chip, profile):
    c = chip(PROGRAM_WITH_DRAWS, profile or quirks(display_wait=True), delay_timer=10).frames(1)
    assert (c.V[1], c.pc, c.delay_timer) == (1, START + 4, 9)
    c.frames(1)
    assert (c.V[1], c.pc, c.delay_timer) == (3, START + 10, 8)
    c.frames(1)
    assert (c.V[1], c.pc) == (14, START + 32)


@pytest.mark.parametrize("profile", ["schip", None])
def test_without_display_wait_a_frame_runs_on(chip, profile):
    c = chip(PROGRAM_WITH_DRAWS, profile or quirks(), delay_timer=10).frames(1)
    assert (c.V[1], c.pc, c.delay_timer) == (9, START + 22, 9)


def test_display_wait_does_not_apply_to_execute(chip):
    c = chip(PROGRAM_WITH_DRAWS, "chip8").step(times=3)
    assert (c.V[1], c.pc) == (2, START + 6)


def test_sprite_as_last_instruction_of_a_frame(chip):
    # The 11th instruction is the DXYN: the next frame starts right after it.
    c = chip([0x7101] * 10 + [0xD001] + [0x7201] * 20, "chip8").frames(1)
    assert (c.V[1], c.pc) == (10, START + 22)
    c.frames(1)
    assert (c.V[2], c.pc) == (11, START + 44)
