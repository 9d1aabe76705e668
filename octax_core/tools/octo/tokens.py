"""Octo's tokens, and the stream the assembler reads them from.

Octo has no grammar beyond whitespace: a token is a run of non-blank characters, or a double-quoted
string with C escapes; `#` starts a comment to the end of the line, even inside a word. A token
that reads as a number is a number (decimal, `0x` hex, `0b` binary, optionally negative, or a
decimal fraction), anything else is a name. Macros work by splicing tokens back into the front of
the stream, so the stream is a stack: the next token is the last element of a reversed list.
"""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Optional, Union

from octax_core.tools.octo.errors import AssemblyError, located

# What C's strtod reads in full, minus the forms no Octo program means as a number (inf, nan).
_DECIMAL = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_HEX = re.compile(r"[+-]?0[xX][0-9a-fA-F]+")
_ESCAPES = {"t": "\t", "n": "\n", "r": "\r", "v": "\v", "0": "\0", "\\": "\\", '"': '"'}
_BLANK = " \t\r\n"


@dataclasses.dataclass(frozen=True)
class Token:
    """One token: `value` is a float for numbers, else the text; `line`/`column` are 1-based.

    `quoted` marks a string literal (Octo treats it as a name otherwise, so `"main"` is `main`).
    `expansion` names the macro call a spliced token came from, for error messages; `depth` counts
    the macro expansions that produced it (0 in the source), which is how the assembler stops a
    macro that calls itself.
    """

    value: Union[float, str]
    line: int
    column: int
    quoted: bool = False
    expansion: Optional[str] = None
    depth: int = 0

    @property
    def is_number(self) -> bool:
        return isinstance(self.value, float)

    def describe(self) -> str:
        """The token as error messages show it: a number, or a quoted name."""
        if self.is_number:
            return _number_text(self.value)
        return f"'{self.value}'"


def _number_text(value: float) -> str:
    return str(int(value)) if value == int(value) else repr(value)


def parse_number(text: str) -> Optional[float]:
    """The number a token spells, or None when it is a name (c-octo's rules).

    Raises:
        OverflowError: the number is beyond a double's range (about 1.8e308).
    """
    if _DECIMAL.fullmatch(text) or _HEX.fullmatch(text):
        value = float(int(text, 16)) if "x" in text.lower() else float(text)
        if math.isinf(value):  # strtod gives inf for 1e400; float() of a long hex int raises
            raise OverflowError(f"{text} is beyond a double's range")
        return value
    for prefix, base in (("0b", 2), ("0x", 16), ("-0b", 2), ("-0x", 16)):
        if text.startswith(prefix):
            # strtol: the longest run of valid digits, 0 when there is none.
            digits = re.match(r"[01]*" if base == 2 else r"[0-9a-fA-F]*", text[len(prefix):]).group()
            value = float(int(digits, base)) if digits else 0.0
            return -value if prefix[0] == "-" else value
    return None


def tokenize(source: str) -> list[Token]:
    """Every token of `source`, in order.

    Raises:
        AssemblyError: an unterminated string, an unknown escape or a number too large for a
            double (with its line and column).
    """
    if source.startswith("\ufeff"):
        source = source[1:]
    tokens: list[Token] = []
    index, line, column, size = 0, 1, 1, len(source)
    while index < size:
        char = source[index]
        if char == "#":
            while index < size and source[index] != "\n":
                index += 1
                column += 1
            continue
        if char in _BLANK:
            index += 1
            line, column = (line + 1, 1) if char == "\n" else (line, column + 1)
            continue
        start_line, start_column = line, column
        if char == '"':
            text, index, line, column = _read_string(source, index, line, column)
            tokens.append(Token(text, start_line, start_column, quoted=True))
            continue
        end = index
        while end < size and source[end] not in _BLANK and source[end] != "#":
            end += 1
        word = source[index:end]
        column += end - index
        index = end
        try:
            number = parse_number(word)
        except OverflowError:
            raise located(f"the number '{word}' is too large: numbers must lie within a double's "
                          "range (about 1.8e308)", source, start_line, start_column) from None
        tokens.append(Token(word if number is None else number, start_line, start_column))
    return tokens


def _read_string(source: str, index: int, line: int, column: int) -> tuple[str, int, int, int]:
    start = (line, column)
    chars = []
    index += 1
    column += 1
    while True:
        if index >= len(source):
            raise located('missing a closing " for this string literal', source, *start)
        char = source[index]
        index += 1
        if char == '"':
            return "".join(chars), index, line, column + 1
        if char == "\n":
            line, column = line + 1, 1
        else:
            column += 1
        if char == "\\":
            if index >= len(source):
                raise located('missing a closing " for this string literal', source, *start)
            escape = source[index]
            if escape not in _ESCAPES:
                raise located(f"unknown escape '\\{escape}' in a string literal; valid escapes: "
                              + " ".join("\\" + e for e in _ESCAPES), source, line, column - 1)
            chars.append(_ESCAPES[escape])
            index += 1
            column += 1
        else:
            chars.append(char)


class TokenStream:
    """The tokens still to read, with room to splice macro expansions in at the front."""

    def __init__(self, source: str, tokens: list[Token]):
        self.source = source
        self._reversed = tokens[::-1]
        self.last: Optional[Token] = None  # the token read most recently: where errors point
        self.end_line, self.end_column = _end_position(source)

    def at_end(self) -> bool:
        return not self._reversed

    def next(self, wanted: str = "a token") -> Token:
        """Reads one token. Raises AssemblyError ("expected <wanted>") at the end of the program."""
        if not self._reversed:
            raise self.error(f"expected {wanted}, but the program ended", at_end=self.last is None)
        self.last = self._reversed.pop()
        return self.last

    def peek(self, ahead: int = 0) -> Optional[Token]:
        """The token `ahead` places on, without reading it; None past the end."""
        return self._reversed[-1 - ahead] if ahead < len(self._reversed) else None

    def peek_is(self, text: str, ahead: int = 0) -> bool:
        token = self.peek(ahead)
        return token is not None and token.value == text

    def match(self, text: str) -> bool:
        """Reads the next token if it is the name `text`."""
        if self.peek_is(text):
            self.next()
            return True
        return False

    def splice(self, tokens: list[Token]) -> None:
        """Puts `tokens` in front of the rest, to be read next and in order."""
        self._reversed.extend(reversed(tokens))

    def error(self, message: str, token: Optional[Token] = None, at_end: bool = False,
              column_offset: int = 0) -> AssemblyError:
        """An AssemblyError at `token` (default: the last token read; at_end: the end of the text)."""
        if at_end:
            return located(message, self.source, self.end_line, self.end_column)
        token = token or self.last
        if token is None:
            return located(message, self.source, 1, 1)
        if token.expansion:
            message = f"{message} (in {token.expansion})"
        return located(message, self.source, token.line, token.column + column_offset)


def _end_position(source: str) -> tuple[int, int]:
    lines = source.split("\n")
    return len(lines), len(lines[-1]) + 1
