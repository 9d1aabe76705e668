"""Octo's compile-time arithmetic: the `{ ... }` of `:calc`, `:byte`, `:org`, `:alias`, `:assert`.

The rules are Octo's, quirks included, so that programs assemble to the bytes Octo gives:
operators have no precedence and group to the right (`{ 10 - 2 - 1 }` is 10 - (2 - 1) = 9), values
are doubles, and the bitwise operators, `%`, `<<` and `>>` work on 32-bit ints truncated toward
zero, as C's `(int)` cast does. A register in an expression is its index (`v3` is 3).
"""

from __future__ import annotations

import math
from typing import Callable, Optional, Protocol

from octax_core.tools.octo.tokens import TokenStream


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
    if right == 0:
        return math.copysign(math.inf, left) * math.copysign(1, right) if left else math.nan
    return left / right


def _sign(value: float) -> float:
    return -1.0 if value < 0 else 1.0 if value > 0 else 0.0


def _safe(function: Callable[[float], float]) -> Callable[[float], float]:
    def call(value: float) -> float:
        try:
            return function(value)
        except (ValueError, OverflowError):
            return math.nan
    return call


UNARY: dict[str, Callable[[float], float]] = {
    "-": lambda v: -v,
    "~": lambda v: float(~_int32(v)),
    "!": lambda v: float(not _int32(v)),
    "sin": math.sin, "cos": math.cos, "tan": math.tan,
    "exp": _safe(math.exp), "log": _safe(math.log), "abs": abs, "sqrt": _safe(math.sqrt),
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
    "pow": lambda a, b: _safe(lambda x: math.pow(x, b))(a),
    "min": min, "max": max,
    "<": lambda a, b: float(a < b), ">": lambda a, b: float(a > b),
    "<=": lambda a, b: float(a <= b), ">=": lambda a, b: float(a >= b),
    "==": lambda a, b: float(a == b), "!=": lambda a, b: float(a != b),
}

NAMED_VALUES = {"PI": math.pi, "E": math.e}


def calculated(stream: TokenStream, context: CalcContext, name: str) -> float:
    """Reads `{ expression }` and returns its value; `name` is what is being computed (for errors)."""
    opening = stream.next("'{'")
    if opening.value != "{":
        raise stream.error(f"expected '{{' to open the expression for {name}, got {opening.describe()}")
    value = _expression(stream, context, name)
    closing = stream.next("'}'")
    if closing.value != "}":
        raise stream.error(f"expected '}}' to close the expression for {name}, got {closing.describe()}; "
                           f"operators: {' '.join(BINARY)}")
    return value


def _expression(stream: TokenStream, context: CalcContext, name: str) -> float:
    if stream.match("strlen"):
        text = stream.next("a string after strlen")
        if text.is_number:
            raise stream.error(f"strlen expects a string, got {text.describe()}")
        return float(len(text.value))
    for operator, function in UNARY.items():
        if stream.match(operator):
            return function(_expression(stream, context, name))
    if stream.match("@"):
        return float(context.rom_byte(_int32(_expression(stream, context, name)) & 0xFFFF))
    left = _terminal(stream, context, name)
    for operator, function in BINARY.items():
        if stream.match(operator):
            right = _expression(stream, context, name)
            try:
                return function(left, right)
            except ZeroDivisionError:
                raise stream.error(f"division by zero when calculating {name}") from None
    return left


def _terminal(stream: TokenStream, context: CalcContext, name: str) -> float:
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
    value = _expression(stream, context, name)
    closing = stream.next("')'")
    if closing.value != ")":
        raise stream.error(f"expected ')' in the expression for {name}, got {closing.describe()}")
    return value
