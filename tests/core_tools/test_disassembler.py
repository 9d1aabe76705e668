"""The Octo disassembler: `assemble(disassemble(rom)) == rom` for every ROM, and readable source.

The round trip is proven three ways: every ROM in ../shared (read in place, never copied), every
one of the 65536 words as a statement, and hypothesis over random byte strings and over random
code-heavy programs whose jumps land anywhere, odd addresses and mid-instruction included.
"""

from __future__ import annotations


import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shared_data import SHARED, TEST_SUITE_DIR

from octax_core import MAX_ROM_SIZE, Rom
from octax_core.tools.octo import assemble
from octax_core.tools.octo.disassembler import decode, disassemble

OCTAX_ROM_DIR = SHARED / "roms" / "octax"  # every file there, not only the games' ROMs
ROMS = sorted(OCTAX_ROM_DIR.glob("*.ch8")) + sorted(TEST_SUITE_DIR.glob("*.ch8"))
START = 0x200
# (opcode, mask of its free bits): the skips, the shifts and XO-CHIP's register-range save
SKIPS_AND_SHIFTS = [(0x3000, 0xFFF), (0x4000, 0xFFF), (0x5000, 0xFF0), (0x9000, 0xFF0), (0xE09E, 0xF00),
                    (0xE0A1, 0xF00), (0x8006, 0xFF0), (0x800E, 0xFF0), (0x5002, 0xFF0)]
SETTINGS = settings(deadline=None, suppress_health_check=[HealthCheck.too_slow])


def round_trips(rom: bytes) -> str:
    source = disassemble(rom)
    assert assemble(source) == rom, source
    return source


def body_lines(source: str) -> list[str]:
    """The source's statements and bytes, without comments, blank lines or indentation."""
    lines = (line.split("#")[0].strip() for line in source.splitlines())
    return [line for line in lines if line]


@pytest.mark.shared
def test_every_shared_rom_is_found():
    # a missing ../shared must fail, not pass vacuously
    assert len([p for p in ROMS if p.parent == TEST_SUITE_DIR]) >= 9
    assert len([p for p in ROMS if p.parent == OCTAX_ROM_DIR]) >= 30


@pytest.mark.shared
@pytest.mark.parametrize("path", ROMS, ids=lambda p: p.name)
def test_shared_roms_round_trip(path):
    round_trips(path.read_bytes())


@SETTINGS
@given(st.binary(max_size=200))
def test_random_bytes_round_trip(rom):
    round_trips(rom)


@settings(SETTINGS, max_examples=10)
@given(st.binary(min_size=MAX_ROM_SIZE, max_size=MAX_ROM_SIZE))
def test_random_full_size_roms_round_trip(rom):
    round_trips(rom)


@st.composite
def programs(draw) -> bytes:
    """Mostly valid instructions, with jump/call/skip/i := targets anywhere in or near the ROM."""
    count = draw(st.integers(1, 100))
    end = START + 2 * count
    target = st.integers(START - 4, end + 4).map(lambda a: a & 0xFFF)
    word = st.one_of(
        st.integers(0, 0xFFFF),
        st.tuples(st.sampled_from([0x1000, 0x2000, 0xA000, 0xB000]), target).map(lambda t: t[0] | t[1]),
        st.tuples(st.sampled_from(SKIPS_AND_SHIFTS), st.integers(0, 0xFFF))
        .map(lambda t: t[0][0] | t[1] & t[0][1]),
        st.just(0xF000),  # i := long: a 4-byte instruction, skipped over as one
    )
    words = draw(st.lists(word, min_size=count, max_size=count))
    data = b"".join(w.to_bytes(2, "big") for w in words)
    return data + draw(st.binary(max_size=1))  # sometimes an odd last byte


@SETTINGS
@given(programs())
def test_random_programs_round_trip(rom):
    round_trips(rom)


def test_every_word_round_trips_as_a_statement():
    """All 65536 words, each as its statement (or its two bytes if it has none), in 37 programs."""
    lines, expected, statements = [], b"", 0
    for word in range(0x10000):
        if word == 0xF000:
            continue  # `i := long` needs its address word: covered below
        instruction = decode(word.to_bytes(2, "big"), START)
        statements += instruction is not None
        lines.append(instruction.statement() if instruction else f"0x{word >> 8:02X} 0x{word & 0xFF:02X}")
        expected += word.to_bytes(2, "big")
        if len(expected) == MAX_ROM_SIZE or word == 0xFFFF:
            assert assemble(": main\n" + "\n".join(lines)) == expected
            lines, expected = [], b""
    assert statements == 48628  # every standard, SCHIP and XO-CHIP encoding Octo writes back


@pytest.mark.parametrize("word, statement", [
    (0x00E0, "clear"), (0x00EE, "return"), (0x00C3, "scroll-down 3"), (0x00D4, "scroll-up 4"),
    (0x00FB, "scroll-right"), (0x00FC, "scroll-left"), (0x00FD, "exit"), (0x00FE, "lores"),
    (0x00FF, "hires"), (0x0123, "native 0x123"), (0x1345, "jump 0x345"), (0x2456, ":call 0x456"),
    (0x3A42, "if va != 0x42 then"), (0x4A42, "if va == 0x42 then"), (0x5AB0, "if va != vb then"),
    (0x9AB0, "if va == vb then"), (0x52A2, "save v2 - va"), (0x52A3, "load v2 - va"),
    (0x6342, "v3 := 0x42"), (0x7AF9, "va += 0xF9"), (0x8390, "v3 := v9"), (0x8AB1, "va |= vb"),
    (0x8AB2, "va &= vb"), (0x8AB3, "va ^= vb"), (0x8AB4, "va += vb"), (0x8AB5, "va -= vb"),
    (0x8AB6, "va >>= vb"), (0x8AB7, "va =- vb"), (0x8ABE, "va <<= vb"), (0xA789, "i := 0x789"),
    (0xB345, "jump0 0x345"), (0xC50F, "v5 := random 0x0F"), (0xD125, "sprite v1 v2 5"),
    (0xE19E, "if v1 -key then"), (0xE1A1, "if v1 key then"), (0xF301, "plane 3"), (0xF002, "audio"),
    (0xF507, "v5 := delay"), (0xF50A, "v5 := key"), (0xF615, "delay := v6"), (0xF618, "buzzer := v6"),
    (0xF21E, "i += v2"), (0xF229, "i := hex v2"), (0xF230, "i := bighex v2"), (0xF733, "bcd v7"),
    (0xF63A, "pitch := v6"), (0xF755, "save v7"), (0xF765, "load v7"), (0xF775, "saveflags v7"),
    (0xF785, "loadflags v7"),
])
def test_each_opcode_reads_as_its_octo_statement(word, statement):
    assert decode(word.to_bytes(2, "big"), START).statement() == statement


@pytest.mark.parametrize("word", [0x0000, 0x5AB1, 0x8AB8, 0x8ABF, 0xE1A0, 0xF401, 0xF0FF])
def test_words_octo_cannot_write_back_are_data(word):
    # 0000 is padding; 5XY1, 8XY8, 8XYF, EXA0, plane 4, F0FF have no Octo statement
    assert decode(word.to_bytes(2, "big"), START) is None
    as_bytes = f"0x{word >> 8:02X} 0x{word & 0xFF:02X}"
    assert body_lines(round_trips(word.to_bytes(2, "big"))) == [": main", as_bytes]


def test_labels_name_call_jump_and_data_targets():
    rom = bytes.fromhex("6000" "220A" "A20E" "120C" "00E0" "00EE" "120C" "3C42")
    assert body_lines(round_trips(rom)) == [
        ": main", "v0 := 0x00", "sub-20A", "i := data-20E", "jump loc-20C",
        "0x00 0xE0",  # never reached: data
        ": sub-20A", "return", ": loc-20C", "jump loc-20C", ": data-20E", "0x3C", "0x42"]


def test_an_opening_jump_forward_becomes_octos_own_jump_main():
    rom = bytes.fromhex("1206" "AAAA" "BBBB" "00E0" "1206")
    source = round_trips(rom)
    assert body_lines(source)[:2] == ["0xAA 0xAA 0xBB 0xBB", ": main"]
    assert "jump main" in body_lines(source)


def test_an_opening_jump_to_0x202_keeps_main_first():
    # `: main` at 0x202 would make Octo drop its jump: so the jump is written out
    source = round_trips(bytes.fromhex("1202" "00E0" "1202"))
    assert body_lines(source)[:3] == [": main", "jump loc-202", ": loc-202"]


def test_code_at_odd_addresses_and_targets_inside_instructions():
    # 0x202 jumps to 0x205 (odd); 0x205's `jump 0x206` lands in its own second byte
    rom = bytes.fromhex("6000" "1205" "FF" "1206" "12")
    assert body_lines(round_trips(rom)) == [
        ": main", "v0 := 0x00", "jump loc-205", "0xFF", ": loc-205", "jump 0x206", "0x12"]


def test_both_sides_of_a_skip_are_code_and_a_skip_steps_over_i_long():
    rom = bytes.fromhex("3000" "F000" "0ABC" "00E0" "00EE")
    assert body_lines(round_trips(rom)) == [
        ": main", "if v0 != 0x00 then", "i := long 0x0ABC", "clear", "return"]


def test_calls_and_targets_outside_the_rom_are_numbers():
    rom = bytes.fromhex("2F00" "A000" "1100")
    assert body_lines(round_trips(rom)) == [": main", ":call 0xF00", "i := 0x000", "jump 0x100"]


def test_sprite_data_is_drawn():
    source = round_trips(bytes.fromhex("A204" "00EE" "3C42"))
    assert "0x3C  # ..####.." in source and "0x42  # .#....#." in source


def test_empty_and_one_byte_roms():
    assert body_lines(round_trips(b"")) == [": main"]
    assert body_lines(round_trips(b"\x12")) == [": main", "0x12"]


def test_accepts_rom_path_and_bytearray(tmp_path):
    rom = bytes.fromhex("00E0" "1200")
    path = tmp_path / "loop.ch8"
    path.write_bytes(rom)
    expected = disassemble(rom)
    assert disassemble(Rom(rom)) == disassemble(path) == disassemble(str(path)) == expected
    assert disassemble(bytearray(rom)) == disassemble(memoryview(rom)) == expected


def test_rejects_oversized_roms_and_other_types():
    with pytest.raises(ValueError, match="3584"):
        disassemble(bytes(MAX_ROM_SIZE + 1))
    with pytest.raises(TypeError, match="Rom, bytes or a file path"):
        disassemble(42)
