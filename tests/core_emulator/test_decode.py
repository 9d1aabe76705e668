"""The decoder and the disassembler read one opcode table (`octax_core.emulator.opcodes`).

On CHIP-8 `decode` looks kinds up in a (16, 256) table indexed by the top nibble and the low byte,
with one extra rule for 0X__; SUPER-CHIP and XO-CHIP read a 65,536-entry table. These tests check,
for all 65,536 words on each platform, that this gives exactly the kind of the first matching row
of the opcode list (NOP for a later platform's row), so the tables can never drift from the list.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from octax_core.emulator.decode import KIND_TABLE, Kind, decode
from octax_core.emulator.opcodes import LEVELS, OPCODES, Flow, kind_on, lookup


@pytest.mark.parametrize("platform", ["chip8", "schip", "xochip"])
def test_decode_gives_every_word_the_kind_of_its_first_matching_opcode_row(platform):
    """On each platform; a row of a later platform is an unknown opcode (NOP)."""
    words = np.arange(0x10000)
    decoded = jax.jit(jax.vmap(lambda w: decode(w >> 8, w & 0xFF, platform).kind))(jnp.asarray(words))
    level = LEVELS[platform]
    expected = [(row.kind if row is not None and row.kind is not None and LEVELS[row.platform] <= level else Kind.NOP)
                for row in map(lookup, words)]
    np.testing.assert_array_equal(np.asarray(decoded), np.array(expected))


def test_every_executed_kind_has_exactly_one_row():
    executed = [row.kind for row in OPCODES if row.kind is not None]
    assert sorted(executed) == sorted(set(Kind) - {Kind.NOP, Kind.STALL})


def test_a_few_words_by_hand():
    assert KIND_TABLE[0x0, 0xE0] == Kind.CLS and KIND_TABLE[0x0, 0xEE] == Kind.RET
    assert KIND_TABLE[0x8, 0x3E] == Kind.SHL and KIND_TABLE[0x8, 0x38] == Kind.NOP  # 8XY8 does not exist
    assert KIND_TABLE[0xF, 0x65] == Kind.LOAD and KIND_TABLE[0xF, 0x30] == Kind.NOP  # FX30: SUPER-CHIP only
    assert lookup(0x00FF).octo == "hires" and lookup(0x00FF).kind is Kind.HIRES and lookup(0x00FF).platform == "schip"
    assert kind_on(0x00FF, "chip8") is Kind.NOP and kind_on(0x00FF, "schip") is Kind.HIRES
    assert kind_on(0xF000, "schip") is Kind.NOP and kind_on(0xF000, "xochip") is Kind.LD_I_LONG
    assert kind_on(0xF100, "xochip") is Kind.NOP and kind_on(0xF301, "xochip") is Kind.PLANE  # X matters here
    assert kind_on(0xF401, "xochip") is Kind.NOP and kind_on(0xFF75, "schip") is Kind.SAVE_FLAGS
    assert lookup(0x2ABC).flow is Flow.CALL and lookup(0x5AB1) is None


def test_rows_are_well_formed():
    for row in OPCODES:
        assert row.pattern & ~row.mask & 0xFFFF == 0, f"{row}: pattern bits outside the mask"
        assert row.platform in ("chip8", "schip", "xochip")
        assert (row.octo is None) == (row.flow is None), row
