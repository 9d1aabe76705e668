"""The Octo assembler: byte-exact on the shared Octo sources, every statement's encoding, the
compile-time language (macros, string modes, :calc), and errors that carry line and column."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared_data import SHARED, TEST_SUITE_DIR

from octax_core import AssemblyError, assemble
from octax_core.tools.octo import assemble_program

OCTAX_ROM_DIR = SHARED / "roms" / "octax"  # the Octo sources are only there, not in the ROM store

SOURCES = sorted(OCTAX_ROM_DIR.glob("*.8o")) + sorted(TEST_SUITE_DIR.glob("*.8o"))


def _reference_rom(source: Path) -> Path:
    """The .ch8 beside a .8o; cavern.8o builds cavern1.ch8 (the others are octax's edits of it)."""
    same_name = source.with_suffix(".ch8")
    return same_name if same_name.exists() else source.with_name(source.stem + "1.ch8")


@pytest.mark.shared
def test_every_shared_source_is_found():
    # 7 octax sources and 9 test-suite sources: a missing folder must fail, not pass vacuously.
    assert len(SOURCES) == 16, [s.name for s in SOURCES]


@pytest.mark.shared
@pytest.mark.parametrize("source", SOURCES, ids=lambda p: p.name)
def test_shared_sources_assemble_byte_exact(source):
    expected = _reference_rom(source).read_bytes()
    assert assemble(source.read_text(encoding="utf-8")) == expected


def body(text: str) -> str:
    """Assembles `: main` + text and returns the program's bytes as hex (no trampoline)."""
    return assemble(": main\n" + text).hex()


# One row per statement form: (Octo, expected bytes). Registers are chosen to be told apart.
ENCODINGS = [
    ("clear", "00e0"), ("return", "00ee"), (";", "00ee"), ("exit", "00fd"),
    ("lores", "00fe"), ("hires", "00ff"), ("scroll-right", "00fb"), ("scroll-left", "00fc"),
    ("scroll-down 3", "00c3"), ("scroll-up 4", "00d4"), ("native 0x123", "0123"),
    ("jump 0x345", "1345"), ("jump0 0x345", "b345"), (":call 0x456", "2456"),
    ("v3 := 0x42", "6342"), ("v3 := -1", "63ff"), ("v3 := v9", "8390"), ("vA += 7", "7a07"),
    ("vA -= 7", "7af9"), ("vA += vB", "8ab4"), ("vA -= vB", "8ab5"), ("vA =- vB", "8ab7"),
    ("vA |= vB", "8ab1"), ("vA &= vB", "8ab2"), ("vA ^= vB", "8ab3"), ("vA >>= vB", "8ab6"),
    ("vA <<= vB", "8abe"), ("v5 := random 0x0F", "c50f"), ("v5 := key", "f50a"),
    ("v5 := delay", "f507"), ("delay := v6", "f615"), ("buzzer := v6", "f618"),
    ("pitch := v6", "f63a"), ("i := 0x789", "a789"), ("i := hex v2", "f229"),
    ("i := bighex v2", "f230"), ("i += v2", "f21e"), ("i := long 0x1234", "f0001234"),
    ("bcd v7", "f733"), ("save v7", "f755"), ("load v7", "f765"), ("save v2 - v5", "5252"),
    ("load v2 - v5", "5253"), ("saveflags v3", "f375"), ("loadflags v3", "f385"),
    ("sprite v1 v2 5", "d125"), ("plane 3", "f301"), ("audio", "f002"),
    ("if v1 == 5 then", "4105"), ("if v1 != 5 then", "3105"), ("if v1 == v2 then", "9120"),
    ("if v1 != v2 then", "5120"), ("if v1 key then", "e1a1"), ("if v1 -key then", "e19e"),
    # Octo's pseudo-ops: vF := operand, vF -= or =- vX, then a skip on vF.
    ("if v1 > v2 then", "8f20 8f15 4f00"), ("if v1 < v2 then", "8f20 8f17 4f00"),
    ("if v1 >= 9 then", "6f09 8f17 3f00"), ("if v1 <= 9 then", "6f09 8f15 3f00"),
    ("0x12 34 0b101 -2", "1222 05fe"), (":byte 0xAB", "ab"), (":byte { 3 * 4 }", "0c"),
    (":pointer 0x1234", "1234"), ("V3 := 1", "6301"),  # register names are case-insensitive
]


@pytest.mark.parametrize("statement,expected", ENCODINGS, ids=[s for s, _ in ENCODINGS])
def test_statement_encoding(statement, expected):
    assert body(statement) == expected.replace(" ", "")


def test_main_trampoline_only_when_main_is_not_first():
    assert assemble(": main\n jump main").hex() == "1200"
    # data before main: a 2-byte `jump main` is reserved at 0x200 and patched at the end
    assert assemble(": data 1 2\n: main\n jump main").hex() == "1204" + "0102" + "1204"


def test_labels_calls_and_forward_references():
    src = ": main\n sub\n jump later\n: sub\n return\n: later\n i := sub\n jump main"
    assert assemble(src).hex() == "2204" "1206" "00ee" "a204" "1200"


def test_control_flow_blocks():
    src = ": main\n if v0 == 1 begin v1 := 2 else v1 := 3 end\n loop v2 += 1 while v2 != 9 again"
    # if-begin: the negated skip, then a jump over the then-part (patched by else/end).
    expected = ["3001", "1208", "6102", "120a", "6103",
                "7201", "4209", "1212", "120a"]  # loop: body, the while's skip + exit jump, again
    assert assemble(src).hex() == "".join(expected)


def test_next_unpack_org_and_alias():
    src = (":alias hi v6 :alias unpack-hi hi\n: main\n :unpack 0xA target\n"
           " :next slot v3 := 0\n:org 0x300\n: target 0xFF")
    program = assemble_program(src)
    rom = program.rom
    assert rom[:4].hex() == "66a3" "6100"  # unpack-hi re-aliased to v6; the nibble sits on top
    assert program.labels["slot"] == 0x205  # :next names the byte after the next one
    assert rom[0x100] == 0xFF and len(rom) == 0x101
    assert program.aliases["hi"] == 6


def test_calc_is_right_associative_with_no_precedence():
    program = assemble_program(":calc A { 10 - 2 - 1 }\n:calc B { 2 * 3 + 4 }\n"
                               ":calc C { ( 2 * 3 ) + 4 }\n:calc D { 7 % 4 << 1 }\n: main")
    assert program.constants["A"] == 9  # 10 - (2 - 1)
    assert program.constants["B"] == 14  # 2 * (3 + 4)
    assert program.constants["C"] == 10
    assert program.constants["D"] == 7  # 7 % (4 << 1)


def test_calc_names_here_and_registers():
    program = assemble_program(": main 1 2 3\n:calc H { HERE }\n:calc R { vC + 1 }\n:calc L { main }")
    assert program.constants["H"] == 0x203 and program.constants["R"] == 13 and program.constants["L"] == 0x200


def test_macros_bind_arguments_and_count_calls():
    src = ":macro pair A B { :byte A :byte B :byte CALLS }\n: main\n pair 1 2\n pair 3 v4"
    with pytest.raises(AssemblyError, match="expected an 8-bit value, but found the register 'v4'"):
        assemble(src)
    assert assemble(src.replace("v4", "4")).hex() == "010200" "030401"


def test_string_modes_expand_per_character():
    src = (':stringmode digits "0123" { :byte { VALUE * 2 } }\n'
           ':stringmode digits "x" { :byte CHAR :byte INDEX }\n: main\n digits "31x0"')
    assert assemble(src).hex() == "0602" "7802" "00"


def test_program_reports_aliases_for_game_specs():
    program = assemble_program(":alias score v5\n:alias lives vE\n: main\n score += 1")
    assert (program.aliases["score"], program.aliases["lives"]) == (5, 14)
    assert program.rom.hex() == "7501"


ERRORS = [
    # (source, line, column, fragment of the message)
    ("", 1, 1, "no 'main' label"),
    (": main\n  v0 := 300\n", 2, 9, "does not fit in a byte"),
    (": main\n  v0 := vz\n", 2, 9, "'vz' is not a defined constant"),
    (": main\n  sprite v0 v1 16\n", 2, 16, "does not fit in 4 bits"),
    (": main\n  jump nowhere\n", 2, 8, "undefined name 'nowhere'"),
    (": main\n  v0 ** v1\n", 2, 6, "unknown operator '**'"),
    (": main\n  if v0 23 2 then\n", 2, 9, "expected a comparison"),
    (": main\n  if v0 == 1\n  v1 := 2\n", 3, 3, "expected 'then' or 'begin'"),
    (": main\n  if v0 == 1 begin\n", 2, 3, "'if ... begin' has no matching 'end'"),
    (": main\n  loop v0 += 1\n", 2, 3, "'loop' has no matching 'again'"),
    (": main\n  end\n", 2, 3, "'end' has no matching"),
    (": main\n  again\n", 2, 3, "'again' has no matching 'loop'"),
    (": main\n  while v0 == 1\n", 2, 3, "not inside a 'loop"),
    (": main\n: main\n", 2, 3, "'main' has already been defined"),
    (": main\n  i -= v0\n", 2, 5, "not an operator for the i register"),
    (": main\n  plane 4\n", 2, 9, "plane bitmask"),
    (": main\n  v0 := 1\n:org 0x200\n  v1 := 2 v2 := 3\n", 4, 9, "data overlap"),
    (": main\n  i := target\n:org 0x2000\n: target\n", 4, 3, "does not fit in the 12 bits"),
    (":macro two A B { :byte A :byte B }\n: main\n  two 1\n", 3, 3, "not enough arguments"),
    (': main\n  "open\n', 2, 3, 'missing a closing "'),
    (': main\n  :byte "\\q"\n', 2, 10, "unknown escape"),
    (":const then 3\n: main\n", 1, 8, "reserved"),
    (":calc X { 1 / }\n: main\n", 1, 15, "undefined name '}'"),
    (":stringmode s \"ab\" { :byte VALUE }\n: main\n  s \"abc\"\n", 3, 8, "not defined for the character 'c'"),
    (":alias x v0\n: x\n", 2, 3, "already used by an alias"),
    (":macro m { v0 := }\n: main\n  m\n", 1, 15, "the program ended"),
]


@pytest.mark.parametrize("source,line,column,fragment", ERRORS, ids=[e[3] for e in ERRORS])
def test_errors_name_line_column_and_problem(source, line, column, fragment):
    with pytest.raises(AssemblyError) as caught:
        assemble(source)
    error = caught.value
    assert fragment in error.message
    assert (error.line, error.column) == (line, column), str(error)
    # str(error) leads with the location and quotes the line with a caret under the column
    text = str(error)
    assert text.startswith(f"line {line}, column {column}: ")
    caret = text.split("\n")[2]
    assert caret == " " * (4 + column - 1) + "^"


def test_error_inside_a_macro_names_the_call_site():
    src = ":macro setx X { v0 := X }\n: main\n  setx 1\n  setx 999\n"
    with pytest.raises(AssemblyError) as caught:
        assemble(src)
    assert "in macro 'setx' called at line 4" in str(caught.value)


def test_rejects_bytes_input():
    with pytest.raises(TypeError, match="Octo source text"):
        assemble(b": main")


# ---- property: random straight-line programs assemble to the encodings they were built from ----

_REG = st.integers(0, 15)
_BYTE = st.integers(0, 255)
_ADDR = st.integers(0x200, 0xFFF)


@st.composite
def _statement(draw) -> tuple[str, str]:
    x, y, nn, nnn, n = draw(_REG), draw(_REG), draw(_BYTE), draw(_ADDR), draw(st.integers(0, 15))
    forms = [
        (f"v{x:x} := {nn}", f"6{x:x}{nn:02x}"), (f"v{x:x} += {nn}", f"7{x:x}{nn:02x}"),
        (f"v{x:x} := v{y:X}", f"8{x:x}{y:x}0"), (f"v{x:x} ^= v{y:x}", f"8{x:x}{y:x}3"),
        (f"v{x:x} -= {nn}", f"7{x:x}{(-nn) & 0xFF:02x}"), (f"v{x:x} =- v{y:x}", f"8{x:x}{y:x}7"),
        (f"i := {nnn:#x}", f"a{nnn:03x}"), (f"jump {nnn}", f"1{nnn:03x}"),
        (f"sprite v{x:x} v{y:x} {n}", f"d{x:x}{y:x}{n:x}"), (f"if v{x:x} != {nn} then", f"3{x:x}{nn:02x}"),
        (f"if v{x:x} == v{y:x} then", f"9{x:x}{y:x}0"), (f"v{x:x} := random {nn:#b}", f"c{x:x}{nn:02x}"),
        (f"bcd v{x:x}", f"f{x:x}33"), (f":byte {nn}", f"{nn:02x}"),
        (f"if v{x:x} > v{y:x} then", f"8f{y:x}08f{x:x}54f00"),
    ]
    return forms[draw(st.integers(0, len(forms) - 1))]


@settings(max_examples=150, deadline=None)
@given(st.lists(_statement(), min_size=1, max_size=40),
       st.sampled_from([" ", "\n", "\t", "  # comment\n"]))
def test_random_programs_assemble_to_their_encodings(statements, separator):
    source = ": main" + separator + separator.join(text for text, _ in statements)
    assert assemble(source).hex() == "".join(code for _, code in statements)


# ---- semantics: the emitted sequences do what the Octo source says, on the reference machine ----

_OPERATORS = {"==": lambda a, b: a == b, "!=": lambda a, b: a != b, "<": lambda a, b: a < b,
              ">": lambda a, b: a > b, "<=": lambda a, b: a <= b, ">=": lambda a, b: a >= b}


def _run_reference(rom: bytes, instructions: int = 200) -> list[int]:
    from reference import RefMachine

    machine = RefMachine(rom, "chip8")
    for _ in range(instructions):
        machine.execute(0)
    return machine.V


@settings(max_examples=120, deadline=None)
@given(st.integers(0, 255), st.integers(0, 255), st.sampled_from(sorted(_OPERATORS)),
       st.booleans())
def test_conditions_branch_as_python_compares(a, b, operator, immediate):
    operand = str(b) if immediate else "v2"
    source = f"""
    : main
      v1 := {a}  v2 := {b}  v3 := 0  v6 := 0
      if v1 {operator} {operand} then v3 := 1
      if v1 {operator} {operand} begin v4 := 1 else v4 := 2 end
      loop
        while v1 {operator} {operand}
        v6 += 1
        if v6 == 3 then jump done
      again
    : done
      jump done
    """
    V = _run_reference(assemble(source))
    holds = _OPERATORS[operator](a, b)
    assert V[3] == int(holds)
    assert V[4] == (1 if holds else 2)
    assert V[6] == (3 if holds else 0)  # while exits the loop as soon as the condition fails
