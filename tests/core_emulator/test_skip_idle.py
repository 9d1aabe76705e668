"""skip_idle is exact: generated programs full of wait loops run bit-identically with and without it.

Each example is a batch of six different programs (their states stacked, so every machine of the
batch runs its own code, as envs of different episodes do), built from blocks that spin in the
ways real games wait: on the delay timer, on a key held or not held, in FX0A, on a jump to itself,
and a counter loop that ends. Between the waits come register work, draws, stores, random numbers
and (on XO-CHIP, SUPER-CHIP's opcodes included) mode switches, scrolls, planes and long I loads,
so a spin may start anywhere in a frame and the detector must restart after every write. Both
machines run the same one-frame calls with the same keys; every field of every state (the
screens included) must match after every frame.
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from reference import RefMachine, first_difference

import octax_core
from octax_core.emulator import idle
from octax_core.emulator.opcodes import Kind
from octax_core.emulator.state import shown

PROGRAM_START = 0x200
BATCH = 6
CALLS = 10  # one-frame run_frames calls per example, each with its own keys
SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# Each machine is two compiled programs (skipping and plain), so the property runs on the two
# most distinct: the VIP's CHIP-8, where a draw ends the frame (display wait) 40 instructions in,
# and XO-CHIP at 30 instructions a frame (two chunks of 15) without display wait, whose programs
# also take every SUPER-CHIP block (mode switches, scrolls, 16x16 sprites, flags) and its own
# (planes, long I, 64 KiB). A SUPER-CHIP machine and a fast CHIP-8 one sit between the two; the
# archive programs (test_archive_platforms.py) run idle skipping on SUPER-CHIP against the
# reference. Both run the folder's batched one-frame program (conftest.py), six machines a batch:
# XO-CHIP's skipping one is test_one_machine.py's plane-2 and GPU-form tests' and
# test_platforms.py's batch test's (one compile for all).
MACHINES = {
    "chip8-vip": dict(platform="chip8", quirks="chip8", instructions_per_frame=40),
    "xochip": dict(platform="xochip", instructions_per_frame=30),
}


def machine_of(name: str, skip_idle: bool) -> octax_core.Machine:
    return octax_core.Machine(**MACHINES[name], skip_idle=skip_idle)


# ---- programs: blocks that are assembled at a known address (jumps point back into them) ----------

def _jump(address):
    return 0x1000 | address


def delay_wait(x):
    """`loop vx := delay if vx != 0 then again`: spins until the delay timer reaches 0."""
    return lambda at: [0xF007 | x << 8, 0x3000 | x << 8, _jump(at)]


def set_delay(x, n):
    return lambda at: [0x6000 | x << 8 | n, 0xF015 | x << 8]


def key_spin(x, key, while_held):
    """Spins while `key` is held (EXA1 skips the jump when it is not) or while it is not (EX9E)."""
    return lambda at: [0x6000 | x << 8 | key, (0xE0A1 if while_held else 0xE09E) | x << 8, _jump(at + 2)]


def key_wait(x):
    return lambda at: [0xF00A | x << 8]


def counter_loop(x, n):
    """`vx := 0 loop vx += 1 if vx != n then again`: a loop that ends, never an exact cycle."""
    return lambda at: [0x6000 | x << 8, 0x7001 | x << 8, 0x3000 | x << 8 | n, _jump(at + 2)]


def jump_self(at):
    return [_jump(at)]


def call_spin(at):
    """A subroutine that returns at once, called in a loop forever: the stack takes part in the cycle."""
    return [0x2000 | (at + 4), _jump(at), 0x00EE]


def alu(words):
    return lambda at: list(words)


def draw(x, y, n, digit):
    return lambda at: [0x6000 | digit << 8, 0xF029, 0xD000 | x << 8 | y << 4 | n]


def store(x, address):
    return lambda at: [0xA000 | address, 0xF055 | x << 8]


nibble = st.integers(0, 14)  # VF is left to the flags
byte = st.integers(0, 255)
alu_word = st.one_of(
    st.tuples(nibble, byte).map(lambda t: 0x6000 | t[0] << 8 | t[1]),
    st.tuples(nibble, byte).map(lambda t: 0x7000 | t[0] << 8 | t[1]),
    st.tuples(nibble, nibble, st.sampled_from([0, 1, 2, 3, 4, 5, 6, 7, 0xE])).map(
        lambda t: 0x8000 | t[0] << 8 | t[1] << 4 | t[2]),
    st.tuples(nibble, byte).map(lambda t: 0xC000 | t[0] << 8 | t[1]),  # RND: the random state moves on
)
common_blocks = [
    st.tuples(nibble).map(lambda t: delay_wait(*t)),
    st.tuples(nibble, st.integers(0, 6)).map(lambda t: set_delay(*t)),
    st.tuples(nibble, st.integers(0, 15), st.booleans()).map(lambda t: key_spin(*t)),
    st.tuples(nibble).map(lambda t: key_wait(*t)),
    st.tuples(nibble, st.integers(1, 40)).map(lambda t: counter_loop(*t)),
    st.just(jump_self),
    st.just(call_spin),
    st.lists(alu_word, min_size=1, max_size=6).map(alu),
    st.tuples(nibble, nibble, st.integers(0, 15), st.integers(0, 15)).map(lambda t: draw(*t)),
    st.tuples(nibble, st.integers(0x300, 0x3F0)).map(lambda t: store(*t)),
]
extended_blocks = [
    st.sampled_from([0x00FF, 0x00FE, 0x00FB, 0x00FC, 0x00C3]).map(lambda word: alu([word])),
    st.tuples(nibble, nibble).map(lambda t: draw(t[0], t[1], 0, 0)),  # 16x16 sprite
    st.tuples(nibble).map(lambda t: alu([0xF075 | min(t[0], 7) << 8])),  # save flags
]
xochip_blocks = [
    st.integers(0, 3).map(lambda p: alu([0xF001 | p << 8])),
    st.integers(0, 15).map(lambda n: alu([0x00D0 | n])),
    st.integers(0x300, 0x1F00).map(lambda a: alu([0xF000, a])),  # long I, then I is reset by the next store
    st.tuples(nibble, nibble).map(lambda t: alu([0x5002 | t[0] << 8 | t[1] << 4])),
]


def blocks_for(name):
    extra = extended_blocks + xochip_blocks if MACHINES[name]["platform"] == "xochip" else []
    return st.lists(st.one_of(*common_blocks, *extra), min_size=1, max_size=8)


def assemble(blocks, prelude) -> bytes:
    words = list(prelude)
    body = PROGRAM_START + 2 * len(words)
    for block in blocks:
        words += block(PROGRAM_START + 2 * len(words))
    words.append(_jump(body))  # back to the first block: the program runs forever
    return b"".join(word.to_bytes(2, "big") for word in words)


def program(name):
    prelude = st.lists(st.tuples(nibble, byte).map(lambda t: 0x6000 | t[0] << 8 | t[1]), min_size=0, max_size=4)
    return st.tuples(blocks_for(name), prelude).map(lambda t: assemble(*t))


def stacked_boot(machine, roms, seed):
    states = [machine.boot(rom, jax.random.key(seed + i)) for i, rom in enumerate(roms)]
    return jax.tree.map(lambda *leaves: jnp.stack(leaves), *states)


def first_mismatch(a, b):
    for path, x in jax.tree_util.tree_flatten_with_path(a)[0]:
        y = functools.reduce(lambda node, key: getattr(node, key.name) if hasattr(key, "name") else node[key.idx],
                             path, b)
        if not np.array_equal(np.asarray(x), np.asarray(y)):
            return jax.tree_util.keystr(path)
    return None


@pytest.mark.parametrize("name", list(MACHINES))
def test_wait_loops_run_bit_identically_with_skip_idle(name, jit_batch_run_frames):
    key_masks = st.lists(st.one_of(st.just(0), st.integers(0, 15).map(lambda k: 1 << k), st.integers(0, 0xFFFF)),
                         min_size=CALLS * BATCH, max_size=CALLS * BATCH)
    machine = machine_of(name, True)
    assert machine.skipping
    skipping = jit_batch_run_frames(machine, 1)
    plain = jit_batch_run_frames(machine_of(name, False), 1)

    @SETTINGS
    @given(roms=st.lists(program(name), min_size=BATCH, max_size=BATCH), keys=key_masks, seed=st.integers(0, 2**16))
    def check(roms, keys, seed):
        fast = slow = stacked_boot(machine, roms, seed)
        keys = np.asarray(keys, np.uint32).reshape(CALLS, BATCH)
        for call in range(CALLS):  # a frame a call: the state, screens included, after every frame
            fast = skipping(fast, keys[call])
            slow = plain(slow, keys[call])
            where = first_mismatch(slow, fast)
            assert where is None, f"frame {call}: {where} differs ({[r.hex() for r in roms]})"

    check()


def test_a_spin_is_skipped_to_the_exact_position_the_frame_would_end_at(jit_run_frames):
    """A 3-instruction delay-timer spin entered mid-frame ends the frame at the pc, and with the
    register values, that running every instruction gives, for frame lengths of every residue
    and chunk (the frame divided into chunks of 5, 13 and 10; a last partial chunk of one at 37,
    which is 997's case too: a chunk of 12 and one instruction over).
    Running every instruction is tests/reference.py's interpreter here, frame by frame (the
    whole snapshot: every field of a CHIP-8 state), so each length compiles one program, not two."""
    rom = assemble([set_delay(1, 5), delay_wait(2)], [])
    ends = set()
    for ipf in (idle.SKIP_FROM, 26, 37, 100):
        fast = octax_core.Machine("chip8", instructions_per_frame=ipf, skip_idle=True)
        assert fast.skipping
        state = fast.boot(rom, jax.random.key(0))
        ref = RefMachine(rom, fast.quirks, ipf, rng=int(octax_core.snapshot(state)["rng"]))
        for frame in range(3):
            state = jit_run_frames(fast)(state, 0, 1)
            ref.run_frame(0)
            difference = first_difference(ref.snapshot(), octax_core.snapshot(state))
            assert difference is None, (ipf, frame, difference)
            ends.add(ref.pc)
        assert ref.delay_timer == 2  # still spinning at the third frame's end
    assert ends == {PROGRAM_START + 4, PROGRAM_START + 6, PROGRAM_START + 8}  # frames end at each of the spin's 3 instructions


def test_pure_kinds_are_the_ones_that_write_no_memory_and_no_screen():
    """The detector's whitelist: every kind that writes memory or the screen (or ends the
    program) is left out, so a cycle is never claimed across a write."""
    writers = {Kind.CLS, Kind.DRW, Kind.BCD, Kind.STORE, Kind.SCROLL_DOWN, Kind.SCROLL_RIGHT, Kind.SCROLL_LEFT,
               Kind.SCROLL_UP, Kind.LORES, Kind.HIRES, Kind.SAVE_RANGE, Kind.EXIT}
    assert not writers & idle.PURE_KINDS
    assert set(Kind) == writers | idle.PURE_KINDS


def test_skip_idle_is_checked():
    with pytest.raises((TypeError, ValueError), match="skip_idle"):
        octax_core.Machine("chip8", skip_idle="yes")


def test_nested_vmap_and_a_single_machine_agree_with_the_plain_loop(jit_run_frames):
    """The batching rule serves one vmap; an outer one (seeds x envs) batches what it returns, and a
    machine outside any vmap runs the unbatched loop: all three give the plain loop's states."""
    rom = assemble([set_delay(1, 3), delay_wait(2), draw(0, 1, 5, 7), key_spin(3, 5, False)], [0x6A07])
    # (100 instructions a frame: the single machine runs the spin test's one-frame program)
    fast = octax_core.Machine("chip8", instructions_per_frame=100, skip_idle=True)
    slow = octax_core.Machine("chip8", instructions_per_frame=100, skip_idle=False)
    keys = np.array([[0, 1 << 5], [1 << 5, 0]], np.uint32)
    seeds = jax.random.split(jax.random.key(1), 4).reshape(2, 2)
    states = jax.vmap(jax.vmap(lambda k: slow.boot(rom, k)))(seeds)
    run = lambda m: jax.jit(jax.vmap(jax.vmap(lambda s, k: m.run_frames(s, k, 3, record_screens=True))))
    a, b = run(fast)(states, keys), run(slow)(states, keys)
    assert first_mismatch(a, b) is None
    one = jax.tree.map(lambda leaf: leaf[1, 0], states)
    plain_state, plain_screens = jax.tree.map(lambda leaf: leaf[1, 0], b)
    for frame in range(3):
        one = jit_run_frames(fast)(one, int(keys[1, 0]), 1)
        assert np.array_equal(np.asarray(shown(one)), np.asarray(plain_screens[frame])), frame
    assert first_mismatch(one, plain_state) is None


def test_chunk_size_wastes_little_of_a_busy_frame():
    """The chunk is 12 unless a busy frame would waste over 3% of its slots in its last partial
    chunk; then it divides the frame (30 -> 15, 100 -> 10)."""
    assert idle.chunk_size(1000) == idle.chunk_size(200) == 12
    assert idle.chunk_size(30) == 15 and idle.chunk_size(100) == 10 and idle.chunk_size(44) == 11
    for ipf in range(idle.SKIP_FROM, 2000):
        chunk = idle.chunk_size(ipf)
        slots = -(-ipf // chunk) * chunk
        assert slots - ipf <= 0.03 * ipf or ipf % chunk == 0 or not any(ipf % d == 0 for d in range(5, 17)), ipf
