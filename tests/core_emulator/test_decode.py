"""The decoder and the disassembler read one opcode table (`octax_core.emulator.opcodes`).

`decode` looks kinds up in a (16, 256) table indexed by the top nibble and the low byte, with one
extra rule for 0X__; these tests check, for all 65,536 words, that this gives exactly the kind of
the first matching row of the opcode list, so the table can never drift from the list.
"""

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.decode import KIND_TABLE, Kind, decode
from octax_core.emulator.opcodes import OPCODES, Flow, lookup


def test_decode_gives_every_word_the_kind_of_its_first_matching_opcode_row():
    words = np.arange(0x10000)
    decoded = jax.jit(jax.vmap(lambda w: decode(w >> 8, w & 0xFF).kind))(jnp.asarray(words))
    expected = [(row.kind if row is not None and row.kind is not None else Kind.NOP) for row in map(lookup, words)]
    np.testing.assert_array_equal(np.asarray(decoded), np.array(expected))


def test_every_executed_kind_has_exactly_one_row():
    executed = [row.kind for row in OPCODES if row.kind is not None]
    assert sorted(executed) == sorted(set(Kind) - {Kind.NOP, Kind.STALL})


def test_a_few_words_by_hand():
    assert KIND_TABLE[0x0, 0xE0] == Kind.CLS and KIND_TABLE[0x0, 0xEE] == Kind.RET
    assert KIND_TABLE[0x8, 0x3E] == Kind.SHL and KIND_TABLE[0x8, 0x38] == Kind.NOP  # 8XY8 does not exist
    assert KIND_TABLE[0xF, 0x65] == Kind.LOAD and KIND_TABLE[0xF, 0x30] == Kind.NOP  # FX30: SUPER-CHIP, not run
    assert lookup(0x00FF).octo == "hires" and lookup(0x00FF).kind is None and lookup(0x00FF).platform == "schip"
    assert lookup(0x2ABC).flow is Flow.CALL and lookup(0x5AB1) is None


def test_rows_are_well_formed():
    for row in OPCODES:
        assert row.pattern & ~row.mask & 0xFFFF == 0, f"{row}: pattern bits outside the mask"
        assert row.platform in ("chip8", "schip", "xochip")
        assert (row.octo is None) == (row.flow is None), row
