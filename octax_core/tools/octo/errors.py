"""`AssemblyError`: what went wrong in an Octo program, and where.

The message is meant to be read by a person or fed back to a program generator (the paper's
compile-errors loop), so it names the line and column (both 1-based), what was expected and what
was found, and quotes the offending source line with a caret under the column.
"""

from __future__ import annotations

from typing import Optional


class AssemblyError(ValueError):
    """An Octo program that does not assemble.

    Attributes:
        message: what was expected and what was found, without the location.
        line: 1-based source line of the token at fault (0 when the whole program is at fault).
        column: 1-based column of that token.
        source_line: the text of that line, without its newline ("" when line is 0).
    """

    def __init__(self, message: str, line: int = 0, column: int = 0, source_line: str = ""):
        self.message = message
        self.line = line
        self.column = column
        self.source_line = source_line
        super().__init__(self._render())

    def _render(self) -> str:
        if self.line <= 0:
            return self.message
        caret = " " * (self.column - 1) + "^"
        return f"line {self.line}, column {self.column}: {self.message}\n    {self.source_line}\n    {caret}"


def located(message: str, source: str, line: int, column: int) -> AssemblyError:
    """An `AssemblyError` at (line, column) of `source`, quoting that line."""
    lines = source.split("\n")
    text: Optional[str] = lines[line - 1] if 0 < line <= len(lines) else ""
    return AssemblyError(message, line, column, text.rstrip("\r").expandtabs(1) if text else "")
