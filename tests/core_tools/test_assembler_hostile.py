"""The assembler on hostile or broken input: every failure is an `AssemblyError` with a line and a
column, in bounded time (issue 38, item 4).

A program generator or a careless user can write a macro that calls itself, an expression that
divides by zero, or a 1,000-term `:calc` chain; none of these may hang the assembler or escape as
a `RecursionError`, `OverflowError` or `ValueError` without a location. The last test feeds a few
hundred mutated copies of our own Octo sources through it to look for any other way out.
"""

from __future__ import annotations

import contextlib
import random
import re
import signal
import time
from pathlib import Path

import pytest

from octax_core import AssemblyError, assemble
from octax_core.tools.octo import assemble_program

ROMS = Path(__file__).resolve().parents[2] / "roms"
SOURCES = sorted(ROMS.glob("*.8o"))


class _TookTooLong(Exception):
    pass


@contextlib.contextmanager
def _time_limit(seconds: float):
    """Raises `_TookTooLong` in the test if the block runs past `seconds` (a hang fails, not stalls)."""
    def expire(signum, frame):
        raise _TookTooLong(f"still running after {seconds} s")
    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _error(source: str, seconds: float = 5.0) -> AssemblyError:
    with _time_limit(seconds), pytest.raises(AssemblyError) as caught:
        assemble(source)
    return caught.value


# ---- macros that never stop expanding ----------------------------------------------------------

def test_a_macro_that_calls_itself_is_an_error_not_a_hang():
    started = time.monotonic()
    error = _error(":macro boom { boom }\n: main\n  boom\n")
    assert time.monotonic() - started < 2
    assert "macro 'boom' expands too deep" in error.message
    assert "calls itself" in error.message
    # the recursive call in the body, and the line that used the macro
    assert (error.line, error.column) == (1, 15), str(error)
    assert "called at line 3" in str(error)


def test_macros_that_call_each_other_are_an_error():
    error = _error(":macro ping { pong }\n:macro pong { ping }\n: main\n  ping\n")
    assert "expands too deep" in error.message and error.line in (1, 2)


def test_a_macro_that_rebuilds_its_own_call_from_its_arguments_is_an_error():
    # `dup dup` expands to `dup dup`: the tokens come from the arguments, not the body.
    error = _error(":macro dup X { X X }\n: main\n  dup dup\n")
    assert "expands too deep" in error.message and error.line >= 1 and error.column >= 1


def test_exponential_macro_expansion_is_capped():
    # m30 expands to 2**30 `:calc`s, which fill no ROM: each macro is shallow, the total is not.
    lines = [":macro m0 { :calc Z { 1 } }"] + [f":macro m{k} {{ m{k - 1} m{k - 1} }}" for k in range(1, 31)]
    started = time.monotonic()
    error = _error("\n".join(lines) + "\n: main\n  m30\n", seconds=20)
    assert time.monotonic() - started < 20  # the bound, on a busy 2-core machine
    assert "macro expansion produced more than 500,000 tokens" in error.message
    assert error.line >= 1 and error.column >= 1


def test_string_mode_that_uses_itself_is_an_error():
    error = _error(':stringmode s "a" { s "a" }\n: main\n  s "a"\n')
    assert "expands too deep" in error.message


def test_deep_but_finite_macro_nesting_still_assembles():
    # 50 macros, each calling the one below: deep enough for any real program, and still fine.
    lines = [":macro m0 X { :byte X }"] + [f":macro m{k} X {{ m{k - 1} X }}" for k in range(1, 50)]
    assert assemble("\n".join(lines) + "\n: main\n  m49 7\n").hex() == "07"


# ---- :calc arithmetic --------------------------------------------------------------------------

CALC_ERRORS = [
    # (expression, column of the operator at fault, fragment of the message)
    ("1 / 0", 13, "division by zero"),
    ("0 / 0", 13, "division by zero"),
    ("1 % 0", 13, "division by zero"),
    ("1e308 * 10", 17, "overflows"),
    ("10 pow 400", 14, "overflows"),
    ("exp 1000", 11, "overflows"),
    ("sqrt -1", 11, "not a real number"),
    ("log -1", 11, "not a real number"),
    ("1 + ( 2 / 0 )", 19, "division by zero"),
]


@pytest.mark.parametrize("expression,column,fragment", CALC_ERRORS, ids=[e[0] for e in CALC_ERRORS])
def test_calc_arithmetic_errors_name_line_and_column(expression, column, fragment):
    error = _error(f": main\n:calc X {{ {expression} }}\n")
    assert fragment in error.message and "the constant 'X'" in error.message
    assert (error.line, error.column) == (2, column), str(error)
    assert str(error).startswith(f"line 2, column {column}: ")


def test_a_number_too_large_for_a_double_is_an_error():
    error = _error(": main\n  :byte { 1e400 }\n")
    assert (error.line, error.column) == (2, 11) and "too large" in error.message
    error = _error(": main\n  v0 := 0x" + "F" * 300 + "\n")
    assert (error.line, error.column) == (2, 9) and "too large" in error.message


def test_calc_results_used_as_values_are_checked_before_use():
    # Before, an infinite result reached int() and escaped as OverflowError, NaN as ValueError.
    assert "division by zero" in _error(":calc X { 1 / 0 }\n: main\n  v0 := X\n").message
    assert "division by zero" in _error(": main\n  :byte { 0 / 0 }\n").message


@pytest.mark.parametrize("terms", [1000, 20000])
def test_long_calc_chains_evaluate(terms):
    chain = " + ".join(["1"] * terms)
    with _time_limit(10):
        program = assemble_program(f":calc X {{ {chain} }}\n: main\n")
    assert program.constants["X"] == terms


def test_deeply_nested_parentheses_and_prefix_operators_evaluate():
    depth = 5000
    with _time_limit(10):
        program = assemble_program(f":calc P {{ {'( ' * depth}3{' )' * depth} }}\n"
                                   f":calc N {{ {'- ' * (depth + 1)}3 }}\n: main\n")
    assert program.constants["P"] == 3 and program.constants["N"] == -3


def test_calc_keeps_octos_grouping():
    # The rewrite without recursion keeps Octo's rules: no precedence, grouping to the right, a
    # prefix operator takes the whole rest, a parenthesis ends a terminal, strlen ends the expression.
    program = assemble_program(":calc A { - 1 + 2 }\n:calc B { ( 1 + 2 ) * 3 }\n"
                               ":calc C { 2 * ( 3 - 1 ) - 1 }\n:calc D { sqrt 16 + 9 }\n"
                               ':calc E { strlen "abc" }\n:calc F { @ 0x1FF + 1 }\n: main\n')
    assert program.constants["A"] == -3 and program.constants["B"] == 9
    assert program.constants["C"] == 2 and program.constants["D"] == 5
    assert program.constants["E"] == 3
    assert program.constants["F"] == 0  # @ (0x1FF + 1): the jump slot at 0x200, still zero
    with pytest.raises(AssemblyError, match="expected '}' to close"):
        assemble(':calc E { strlen "abc" + 1 }\n: main\n')


# ---- property: mutated real programs assemble or raise AssemblyError ---------------------------

_TOKEN = re.compile(r'"(?:[^"\\]|\\.)*"|[^\s]+')
# Tokens that reach the corners: the compile-time language, flow, braces and odd numbers.
_VOCABULARY = (":macro", ":calc", ":const", ":alias", ":org", ":byte", ":pointer", ":next", ":unpack",
               ":stringmode", ":assert", ":call", "long", "{", "}", "(", ")", "/", "0", "%", "pow",
               "sqrt", "log", "@", "strlen", "HERE", "CALLS", "1e400", "-1e308", "0x10000", "0b",
               "0xFFFFFFFFFF", "65535", "-129", "if", "begin", "else", "end", "loop", "while", "again",
               ":", "main", "v0", "vF", "i", ":=", "+=", "-=", "key", "then", "jump", "sprite",
               '"x"', '"\\n"', "# a comment", "boom", ":macro boom { boom }", "hires", "plane", "3", "return")


def _mutated(rng: random.Random, source: str) -> str:
    """`source` with 1 to 4 random edits: whole lines (most of which still assemble) or tokens
    (most of which do not) deleted, duplicated, swapped, copied elsewhere or replaced."""
    lines = [_TOKEN.findall(line) for line in re.sub(r"#[^\n]*", "", source).split("\n")]
    lines = [line for line in lines if line]  # comments out, so the edits land on code
    for _ in range(rng.randint(1, 4)):
        at, other = rng.randrange(len(lines)), rng.randrange(len(lines))
        line = lines[at]
        spot = rng.randrange(len(line))
        edit = rng.randrange(8)
        if edit == 0:
            del lines[at]
        elif edit == 1:
            lines.insert(other, list(line))
        elif edit == 2:
            lines[at], lines[other] = lines[other], lines[at]
        elif edit == 3:
            del line[spot]
        elif edit == 4:
            line.insert(spot, line[spot])
        elif edit == 5:
            line[spot] = rng.choice(_VOCABULARY)
        elif edit == 6:
            line.insert(spot, rng.choice(_VOCABULARY))
        else:
            donor = lines[other]
            start = rng.randrange(len(donor))
            line[spot:spot] = donor[start:start + rng.randint(1, 12)]
        lines = [line for line in lines if line]
        if not lines:
            break
    return "\n".join(" ".join(line) for line in lines)


def test_our_sources_are_found():
    assert len(SOURCES) >= 4, SOURCES  # an empty list would make the next test pass vacuously


def test_mutated_programs_assemble_or_raise_assembly_error(tmp_path):
    rng = random.Random(38)
    texts = [path.read_text(encoding="utf-8") for path in SOURCES]
    outcomes = {"assembled": 0, "AssemblyError": 0}
    started = time.monotonic()
    for case in range(300):
        source = _mutated(rng, rng.choice(texts))
        try:
            with _time_limit(5):
                assemble(source)
            outcomes["assembled"] += 1
        except AssemblyError as error:
            assert error.line >= 1 and error.column >= 1, (case, str(error))
            outcomes["AssemblyError"] += 1
        except Exception as error:  # any other way out is the bug this test looks for
            kept = tmp_path / f"case-{case}.8o"
            kept.write_text(source, encoding="utf-8")
            raise AssertionError(f"case {case}: {type(error).__name__}: {error} (source: {kept})") from error
    # Both outcomes occur, so the mutations neither always break nor never touch the programs.
    assert outcomes["assembled"] > 10 and outcomes["AssemblyError"] > 10, outcomes
    assert time.monotonic() - started < 60
