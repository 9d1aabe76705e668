"""Property tests for SUPER-CHIP and XO-CHIP: random programs mixing the new opcodes with the old
run the same on the JAX core and on tests/reference.py, instruction by instruction and frame by
frame (see test_random_programs.py for the CHIP-8 properties and the program shape).

The new opcodes come often: mode switches, scrolls in every direction, 16x16 sprites, big digits,
flag registers, and on XO-CHIP plane selection, register ranges, F000 NNNN (two words; skips
over it jump 4 bytes), audio and pitch; 00FD, which ends the program, is rare. Each platform runs
under its own quirk profile and under a mix that the profile does not cover.
"""

import jax
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from reference import RefMachine, first_difference
from test_random_programs import (address, assert_frames_match, assert_instructions_match, byte, common, key_mask,
                                  nibble, xnn, xyn)

import octax_core

CASES = {
    "schip": ("schip", None),
    "schip-mixed": ("schip", octax_core.Quirks(vf_reset=True, memory_increment=True, display_wait=True,
                                              clipping=False, shift_uses_vy=True, jump_uses_vx=False)),
    "xochip": ("xochip", None),
    "xochip-mixed": ("xochip", octax_core.Quirks(vf_reset=False, memory_increment=False, display_wait=False,
                                                clipping=True, shift_uses_vy=False, jump_uses_vx=True)),
}
STEPS = 96
FRAMES = 4
INSTRUCTIONS_PER_FRAME = 11  # test_reference_platforms.py runs its ROMs on these machines too (one compile)
PROGRAM_START = 0x200
SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
FAST_EXAMPLES = 20  # in make test; make test-slow runs SETTINGS's count too (the `_all_examples` twins)


def fast_and_full(test, parametrize):
    fast = parametrize(settings(SETTINGS, max_examples=FAST_EXAMPLES)(test()))
    return fast, pytest.mark.slow(parametrize(SETTINGS(test())))

schip_only = [
    st.sampled_from([0x00FB, 0x00FC, 0x00FE, 0x00FF, 0x00FF]),
    nibble.map(lambda n: 0x00C0 | n),
    xyn(0xD000, st.just(0)),  # 16x16
    xyn(0xD000),  # more sprites, so that scrolls and planes have pixels to move
    xnn(0xF000, st.sampled_from([0x30, 0x75, 0x85])),
]
xochip_only = [
    nibble.map(lambda n: 0x00D0 | n),
    xyn(0x5000, st.sampled_from([2, 3])),
    st.integers(0, 3).map(lambda n: 0xF001 | n << 8),
    st.just(0xF002),
    xnn(0xF000, st.just(0x3A)),
    # F000 NNNN: two words, the address anywhere in 64 KiB, often near the ends
    st.one_of(st.integers(0, 0xFFFF), st.integers(0xFFC0, 0xFFFF), st.integers(0x200, 0x280)).map(lambda a: ("long", a)),
]
jump = st.tuples(st.sampled_from([0x1000, 0x2000, 0xB000]), st.integers(0, 63), st.booleans())
rare = [st.sampled_from([0x00E0, 0x00EE, 0x00FD]), st.integers(0, 0xFFFF)]


def instructions(platform):
    new = schip_only + (xochip_only if platform == "xochip" else [])
    return st.one_of(*common, *new, *new, jump, *rare)


@st.composite
def programs(draw, platform):
    prelude = [0x6000 | (k << 8) | draw(byte) for k in range(16)]
    prelude.append(0xA000 | draw(st.one_of(address, st.integers(0xA0, 0x13F))))  # lit bytes: code, fonts
    body = draw(st.lists(instructions(platform), min_size=4, max_size=48))
    words = prelude[:]
    for item in body:  # expand F000 NNNN first, so that jump slots count words
        words.extend([0xF000, item[1]] if isinstance(item, tuple) and item[0] == "long" else [item])
    slots = len(words)
    for i, item in enumerate(words):
        if isinstance(item, tuple):  # (family, slot, odd): a jump into the program
            family, slot, odd = item
            words[i] = family | (PROGRAM_START + 2 * (slot % slots) + int(odd))
    words.append(0x1000 | (PROGRAM_START + 2 * len(prelude)))  # loop over the body
    return b"".join(word.to_bytes(2, "big") for word in words)


def boot_both(rom, case, seed):
    platform, quirks = CASES[case]
    machine = octax_core.Machine(platform, quirks=quirks, instructions_per_frame=INSTRUCTIONS_PER_FRAME)
    state = machine.boot(rom, jax.random.key(seed))
    snap = octax_core.snapshot(state)
    ref = RefMachine(rom, machine.quirks, INSTRUCTIONS_PER_FRAME, rng=int(snap["rng"]), platform=platform)
    assert first_difference(ref.snapshot(), snap) is None
    return machine, state, ref


def case_programs(case):
    return programs(CASES[case][0])


def instructions_property():
    @given(data=st.data(), keys=st.lists(key_mask, min_size=STEPS, max_size=STEPS), seed=st.integers(0, 2**32 - 1))
    def test_instructions_match_reference(case, data, keys, seed, jit_execute):
        rom = data.draw(case_programs(case), label="rom")
        machine, state, ref = boot_both(rom, case, seed)
        assert_instructions_match(case, jit_execute(machine), state, ref, keys, rom)
    return test_instructions_match_reference


test_instructions_match_reference, test_instructions_match_reference_all_examples = fast_and_full(
    instructions_property, pytest.mark.parametrize("case", CASES))


def frames_property():
    @given(data=st.data(), keys=st.lists(key_mask, min_size=FRAMES, max_size=FRAMES), seed=st.integers(0, 2**32 - 1))
    def test_frames_match_reference(case, data, keys, seed, jit_run_frames):
        rom = data.draw(case_programs(case), label="rom")
        machine, state, ref = boot_both(rom, case, seed)
        assert_frames_match(case, jit_run_frames(machine), state, ref, keys, rom)
    return test_frames_match_reference


test_frames_match_reference, test_frames_match_reference_all_examples = fast_and_full(
    frames_property, pytest.mark.parametrize("case", CASES))
