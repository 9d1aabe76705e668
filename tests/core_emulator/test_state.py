"""Host-side views and edits of a state: snapshot, poke (and the RAM mirror it maintains), render_text."""

import jax
import numpy as np

import octax_core
from octax_core.emulator.state import MEMORY_OFFSET, MIRROR_SIZE

PROGRAM = bytes([0x12, 0x00])  # 1200: jump to self


def _boot(machine=octax_core.Machine("chip8")):
    return machine.boot(PROGRAM, jax.random.key(0))


def test_snapshot_has_the_documented_fields():
    snap = octax_core.snapshot(_boot())
    expected = {"V": ((16,), np.uint8), "I": ((), np.uint16), "pc": ((), np.uint16), "sp": ((), np.uint8),
                "stack": ((16,), np.uint16), "memory": ((4096,), np.uint8), "delay_timer": ((), np.uint8),
                "sound_timer": ((), np.uint8), "screen": ((32, 64), np.bool_), "rng": ((), np.uint32),
                "key_wait": ((), np.uint8)}
    assert {name: (value.shape, value.dtype) for name, value in snap.items()} == expected
    assert snap["memory"][0x50:0xA0].tobytes() == octax_core.FONT
    assert snap["memory"][0x200:0x202].tobytes() == PROGRAM
    assert int(snap["pc"]) == 0x200 and int(snap["rng"]) != 0


def test_poke_wraps_and_keeps_the_mirror():
    state = octax_core.poke(_boot(), 0xFFE, bytes([1, 2, 3, 4]))
    ram = octax_core.snapshot(state)["memory"]
    assert list(ram[0xFFE:]) == [1, 2] and list(ram[:2]) == [3, 4]
    stored = np.asarray(state.memory)
    tail = stored[MEMORY_OFFSET + 4096 :]
    assert len(tail) == MIRROR_SIZE and list(tail[:16]) == list(ram[:16])


def test_poke_then_fx65_near_the_end_reads_through_the_wrap():
    # A6FE; F365: load V0..V3 from 0xFFE, 0xFFF, 0x000, 0x001.
    machine = octax_core.Machine(quirks="schip")
    state = machine.boot(bytes([0xAF, 0xFE, 0xF3, 0x65]), jax.random.key(0))
    state = octax_core.poke(state, 0xFFE, bytes([9, 8, 7, 6]))
    state = machine.execute(machine.execute(state, 0), 0)
    assert list(octax_core.snapshot(state)["V"][:4]) == [9, 8, 7, 6]


def test_render_text_draws_lit_pixels():
    # 00E0; A050 (font "0"); D015 at (0, 0): the 4x5 glyph of 0 in the top-left corner.
    machine = octax_core.Machine(quirks="schip")
    state = machine.boot(bytes([0x00, 0xE0, 0xA0, 0x50, 0xD0, 0x15]), jax.random.key(0))
    for _ in range(3):
        state = machine.execute(state, 0)
    lines = octax_core.render_text(state).splitlines()
    assert len(lines) == 32 and all(len(line) == 64 for line in lines)
    assert [line[:4] for line in lines[:5]] == ["####", "#..#", "#..#", "#..#", "####"]
    assert set("".join(lines[5:])) == {"."}
