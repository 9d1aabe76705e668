"""Octo's compile-time arithmetic: the `{ ... }` of `:calc`, `:byte`, `:org`, `:alias`, `:assert`.

The rules are Octo's, quirks included, so that programs assemble to the bytes Octo gives:
operators have no precedence and group to the right (`{ 10 - 2 - 1 }` is 10 - (2 - 1) = 9), values
are doubles, and the bitwise operators, `%`, `<<` and `>>` work on 32-bit ints truncated toward
zero, as C's `(int)` cast does. A register in an expression is its index (`v3` is 3).

One departure: where Octo lets a division by zero, an overflow or a domain error (`sqrt -1`) give
inf or NaN and casts that to an int (undefined in C), this is an `AssemblyError` at the operator.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Callable, Optional, Protocol

from octax_core.tools.octo.tokens import Token, TokenStream


class CalcContext(Protocol):
    """What expressions may read from the assembler."""

    here: int

    def register_index(self, name: str) -> Optional[int]: ...
    def constant(self, name: str) -> Optional[float]: ...
    def is_forward_reference(self, name: str) -> bool: ...
    def rom_byte(self, address: int) -> int: ...


def _int32(value: float) -> int:
    """C's `(int)value` on the values Octo programs use: truncate, then wrap to 32 bits."""
    if math.isnan(value) or math.isinf(value):
        return -(2 ** 31)
    number = int(value) & 0xFFFFFFFF
    return number - (1 << 32) if number & 0x80000000 else number


def _c_modulo(left: float, right: float) -> float:
    a, b = _int32(left), _int32(right)
    if b == 0:
        raise ZeroDivisionError("% by zero")
    return float(int(math.fmod(a, b)))


def _divide(left: float, right: float) -> float:
    # C gives inf or NaN here; an Octo program that divides by zero has a bug, so it is an error.
    if right == 0:
        raise ZeroDivisionError("/ by zero")
    return left / right


def _sign(value: float) -> float:
    return -1.0 if value < 0 else 1.0 if value > 0 else 0.0


UNARY: dict[str, Callable[[float], float]] = {
    "-": lambda v: -v,
    "~": lambda v: float(~_int32(v)),
    "!": lambda v: float(not _int32(v)),
    "sin": math.sin, "cos": math.cos, "tan": math.tan,
    "exp": math.exp, "log": math.log, "abs": abs, "sqrt": math.sqrt,
    "sign": _sign, "ceil": lambda v: float(math.ceil(v)), "floor": lambda v: float(math.floor(v)),
}

BINARY: dict[str, Callable[[float, float], float]] = {
    "-": lambda a, b: a - b,
    "+": lambda a, b: a + b,
    "*": lambda a, b: a * b,
    "/": _divide,
    "%": _c_modulo,
    "&": lambda a, b: float(_int32(a) & _int32(b)),
    "|": lambda a, b: float(_int32(a) | _int32(b)),
    "^": lambda a, b: float(_int32(a) ^ _int32(b)),
    "<<": lambda a, b: float(_int32(_int32(a) << (_int32(b) & 31))),
    ">>": lambda a, b: float(_int32(a) >> (_int32(b) & 31)),
    "pow": math.pow,
    "min": min, "max": max,
    "<": lambda a, b: float(a < b), ">": lambda a, b: float(a > b),
    "<=": lambda a, b: float(a <= b), ">=": lambda a, b: float(a >= b),
    "==": lambda a, b: float(a == b), "!=": lambda a, b: float(a != b),
}

NAMED_VALUES = {"PI": math.pi, "E": math.e}


def calculated(stream: TokenStream, context: CalcContext, name: str) -> float:
    """Reads `{ expression }` and returns its value; `name` is what is being computed (for errors).

    Raises:
        AssemblyError: a malformed expression, an undefined name, or arithmetic with no finite
            result (division by zero, overflow, a domain error such as `sqrt -1`), at the
            operator's line and column.
    """
    opening = stream.next("'{'")
    if opening.value != "{":
        raise stream.error(f"expected '{{' to open the expression for {name}, got {opening.describe()}")
    value = _expression(stream, context, name)
    closing = stream.next("'}'")
    if closing.value != "}":
        raise stream.error(f"expected '}}' to close the expression for {name}, got {closing.describe()}; "
                           f"operators: {' '.join(BINARY)}")
    return value


@dataclasses.dataclass(frozen=True)
class _Pending:
    """An operator still waiting for the expression to its right, or an open parenthesis.

    `kind` is "unary", "binary" (with `left`, its left operand), "@" (a ROM byte) or "(".
    """

    operator: Token
    kind: str
    function: Optional[Callable[..., float]] = None
    left: float = 0.0


def _expression(stream: TokenStream, context: CalcContext, name: str) -> float:
    """Octo's grammar, `expr := strlen STRING | UNARY expr | '@' expr | terminal [BINARY expr]`
    with `terminal := value | '(' expr ')'`, evaluated with a stack of pending operators instead
    of recursion, so that a 20,000-term chain or 5,000 nested parentheses evaluate like short
    ones instead of ending in a RecursionError."""
    pending: list[_Pending] = []
    while True:
        complete = False  # a whole expression (no binary operator may follow it), not a terminal
        if stream.match("strlen"):
            text = stream.next("a string after strlen")
            if text.is_number:
                raise stream.error(f"strlen expects a string, got {text.describe()}")
            value, complete = float(len(text.value)), True
        elif _prefix(stream, pending):
            continue
        else:
            value = _terminal(stream, context, name)
            if value is None:
                pending.append(_Pending(stream.last, "("))
                continue
        while True:
            if not complete and _infix(stream, pending, value):
                break  # on to its right operand
            if not pending:
                return value
            top = pending.pop()
            if top.kind == "(":
                closing = stream.next("')'")
                if closing.value != ")":
                    raise stream.error(f"expected ')' in the expression for {name}, got {closing.describe()}")
                complete = False  # `( ... )` is a terminal: a binary operator may follow
            else:
                value, complete = _apply(stream, context, top, value, name), True


def _prefix(stream: TokenStream, pending: list[_Pending]) -> bool:
    """Reads a unary operator or `@` if one is next, and leaves it pending."""
    operator = _peek_name(stream)
    if operator in UNARY:
        pending.append(_Pending(stream.next(), "unary", UNARY[operator]))
        return True
    if operator == "@":
        pending.append(_Pending(stream.next(), "@"))
        return True
    return False


def _infix(stream: TokenStream, pending: list[_Pending], left: float) -> bool:
    """Reads a binary operator if one is next, and leaves it pending with its left operand."""
    operator = _peek_name(stream)
    if operator in BINARY:
        pending.append(_Pending(stream.next(), "binary", BINARY[operator], left))
        return True
    return False


def _peek_name(stream: TokenStream) -> Optional[str]:
    """The next token's text if it is a name (or string), else None: one look instead of a
    `match` per operator, which made macro-heavy programs slow."""
    token = stream.peek()
    return None if token is None or token.is_number else token.value


def _apply(stream: TokenStream, context: CalcContext, op: _Pending, right: float, name: str) -> float:
    """`op` applied to `right` (and its left operand). Octo computes in C doubles and lets inf and
    NaN flow on into `(int)` casts, whose result C leaves undefined; here any result that is not
    finite is an error at the operator, so a program's bytes never depend on such a cast."""
    if op.kind == "@":
        return float(context.rom_byte(_int32(right) & 0xFFFF))
    shown = f"{op.operator.value} {_shown(right)}"
    if op.kind == "binary":
        shown = f"{_shown(op.left)} {shown}"
    try:
        result = op.function(op.left, right) if op.kind == "binary" else op.function(right)
    except ZeroDivisionError:
        raise stream.error(f"division by zero when calculating {name} ({shown})", op.operator) from None
    except OverflowError:
        result = math.inf
    except ValueError:  # math's domain errors: sqrt -1, log 0, pow -8 0.5
        result = math.nan
    if math.isinf(result):
        raise stream.error(f"{shown} overflows when calculating {name}: the result is too large "
                           "for a double (about 1.8e308 at most)", op.operator)
    if math.isnan(result):
        raise stream.error(f"{shown} is not a real number (a domain error) when calculating {name}",
                           op.operator)
    return float(result)


def _shown(value: float) -> str:
    return f"{value:g}"


def _terminal(stream: TokenStream, context: CalcContext, name: str) -> Optional[float]:
    """The value of a number, register, constant or label; None for `(`, which opens a group."""
    token = stream.next("a number, name or '(' in the expression")
    if token.is_number:
        return token.value
    text = token.value
    register = context.register_index(text)
    if register is not None:
        return float(register)
    if text in NAMED_VALUES:
        return NAMED_VALUES[text]
    if text == "HERE":
        return float(context.here)
    if context.is_forward_reference(text):
        raise stream.error(f"cannot use the forward reference '{text}' when calculating {name}: "
                           "define the label before this line")
    value = context.constant(text)
    if value is not None:
        return value
    if text != "(":
        raise stream.error(f"undefined name {token.describe()} when calculating {name}")
    return None
