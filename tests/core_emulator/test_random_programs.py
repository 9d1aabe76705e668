"""Property tests: random programs run the same on the JAX core and on tests/reference.py.

A program is a prelude that loads every register and I with random values, then a body of
random instructions, biased toward valid opcodes, with jump and call targets inside the program
so that it keeps running its own code. Both machines run it one instruction at a time with
random keys, and the whole snapshot must match after every instruction; a second property
runs whole frames. Three quirk sets: the two profiles and a mix that neither covers (sprites wrap).
"""

import jax
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from reference import RefMachine, first_difference

import octax_core

QUIRK_SETS = {
    "chip8": "chip8",
    "schip": "schip",
    "mixed": octax_core.Quirks(vf_reset=True, memory_increment=False, display_wait=True,
                               clipping=False, shift_uses_vy=False, jump_uses_vx=True),
}
STEPS = 96  # instructions per example, prelude included
FRAMES = 4
INSTRUCTIONS_PER_FRAME = 11
PROGRAM_START = 0x200
SETTINGS = settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
# `make test` runs each property with FAST_EXAMPLES fresh examples, `make test-slow` with all of
# SETTINGS's too (the `_all_examples` twins): the same property, a smaller sample of it per run.
FAST_EXAMPLES = 30


def fast_and_full(test, parametrize):
    """The property `test` (given-decorated, unsettled) as two pytest tests: FAST_EXAMPLES
    examples, and SETTINGS's count marked slow."""
    fast = parametrize(settings(SETTINGS, max_examples=FAST_EXAMPLES)(test()))
    return fast, pytest.mark.slow(parametrize(SETTINGS(test())))


# ---- programs ------------------------------------------------------------------------------------

nibble = st.integers(0, 15)
byte = st.one_of(st.integers(0, 255), st.sampled_from([0, 1, 0x7F, 0x80, 0xFF]))
address = st.one_of(st.integers(0x200, 0x280), st.integers(0x50, 0x9F),
                    st.integers(0xFF0, 0xFFF), st.integers(0, 0xFFF))
key_mask = st.one_of(st.just(0), st.integers(0, 15).map(lambda k: 1 << k), st.integers(0, 0xFFFF))


def xnn(family, nn=byte):
    """family | x << 8 | nn"""
    return st.tuples(nibble, nn).map(lambda t: family | t[0] << 8 | t[1])


def xyn(family, n=nibble):
    """family | x << 8 | y << 4 | n"""
    return st.tuples(nibble, nibble, n).map(lambda t: family | t[0] << 8 | t[1] << 4 | t[2])


# A jump is (family, slot, odd): the target is a program slot, resolved once the length is known.
jump = st.tuples(st.sampled_from([0x1000, 0x2000, 0xB000]), st.integers(0, 63), st.booleans())

common = [
    xnn(0x6000), xnn(0x7000),
    xyn(0x8000, st.sampled_from([0x0, 0x1, 0x2, 0x3, 0x4, 0x5, 0x6, 0x7, 0xE])),
    xnn(0x3000), xnn(0x4000), xyn(0x5000, st.just(0)), xyn(0x9000, st.just(0)),
    address.map(lambda a: 0xA000 | a),
    xnn(0xC000),
    xyn(0xD000),
    xnn(0xE000, st.sampled_from([0x9E, 0xA1])),
    xnn(0xF000, st.sampled_from([0x07, 0x0A, 0x15, 0x18, 0x1E, 0x29, 0x33, 0x55, 0x65])),
]
rare = [
    st.sampled_from([0x00E0, 0x00EE]),  # an unmatched return leaves the program for a while
    st.integers(0, 0xFFFF),  # anything, unknown opcodes and wild jumps included
]
instruction = st.one_of(*common, *common, jump, *rare)


@st.composite
def programs(draw):
    prelude = [0x6000 | (k << 8) | draw(byte) for k in range(16)]
    prelude.append(0xA000 | draw(address))
    body = draw(st.lists(instruction, min_size=4, max_size=48))
    slots = len(prelude) + len(body)
    words = prelude[:]
    for item in body:
        if isinstance(item, tuple):  # (family, slot, odd): a jump into the program
            family, slot, odd = item
            words.append(family | (PROGRAM_START + 2 * (slot % slots) + int(odd)))
        else:
            words.append(item)
    words.append(0x1000 | (PROGRAM_START + 2 * len(prelude)))  # loop over the body
    return b"".join(word.to_bytes(2, "big") for word in words)


def listing(rom):
    return " ".join(rom[i:i + 2].hex().upper() for i in range(0, len(rom), 2))


def boot_both(rom, quirks, seed):
    machine = octax_core.Machine(quirks=quirks, instructions_per_frame=INSTRUCTIONS_PER_FRAME)
    state = machine.boot(rom, jax.random.key(seed))
    snap = octax_core.snapshot(state)
    ref = RefMachine(rom, machine.quirks, INSTRUCTIONS_PER_FRAME, rng=int(snap["rng"]))
    assert first_difference(ref.snapshot(), snap) is None
    return machine, state, ref


# ---- properties ----------------------------------------------------------------------------------

def instructions_property():
    @given(rom=programs(), keys=st.lists(key_mask, min_size=STEPS, max_size=STEPS),
           seed=st.integers(0, 2**32 - 1))
    def test_instructions_match_reference(quirk_set, rom, keys, seed, jit_execute):
        machine, state, ref = boot_both(rom, QUIRK_SETS[quirk_set], seed)
        assert_instructions_match(quirk_set, jit_execute(machine), state, ref, keys, rom)
    return test_instructions_match_reference


test_instructions_match_reference, test_instructions_match_reference_all_examples = fast_and_full(
    instructions_property, pytest.mark.parametrize("quirk_set", QUIRK_SETS))


def assert_instructions_match(label, execute, state, ref, keys, rom):
    """Runs one instruction per key mask on both machines; every snapshot must match. `execute`
    is the session's jitted `machine.execute` (tests/conftest.py), the program the per-opcode
    tests and the hand programs run: one compile per machine for all of them."""
    for step, mask in enumerate(keys):
        pc = ref.pc
        opcode = ref.execute(mask)
        state = execute(state, mask)
        difference = first_difference(ref.snapshot(), octax_core.snapshot(state))
        assert difference is None, (
            f"[{label}] instruction {step}, pc={pc:#06x} opcode={opcode:04X}, keys={mask:#06x}: "
            f"{difference}\n  program: {listing(rom)}")


def assert_frames_match(label, run, state, ref, keys, rom):
    """Runs one frame per key mask on both machines; every snapshot must match."""
    for frame, mask in enumerate(keys):
        pc = ref.pc
        ref.run_frame(mask)
        state = run(state, mask, 1)
        difference = first_difference(ref.snapshot(), octax_core.snapshot(state))
        assert difference is None, (
            f"[{label}] frame {frame} from pc={pc:#06x}, keys={mask:#06x}: {difference}\n"
            f"  program: {listing(rom)}")


def frames_property():
    @given(rom=programs(), keys=st.lists(key_mask, min_size=FRAMES, max_size=FRAMES),
           seed=st.integers(0, 2**32 - 1))
    def test_frames_match_reference(quirk_set, rom, keys, seed, jit_run_frames):
        machine, state, ref = boot_both(rom, QUIRK_SETS[quirk_set], seed)
        assert_frames_match(quirk_set, jit_run_frames(machine), state, ref, keys, rom)
    return test_frames_match_reference


test_frames_match_reference, test_frames_match_reference_all_examples = fast_and_full(
    frames_property, pytest.mark.parametrize("quirk_set", QUIRK_SETS))
