"""Checks for user-given settings, shared by every layer, with one wording for each problem.

Bad input raises at once with a message that names the setting, what it must be and what it
got, never a silent clamp: `check_int("num_envs", 0)` raises "num_envs must be an int >= 1,
got 0". numpy integers count as ints; bools do not (True is not a frame count).
"""

from __future__ import annotations

import operator
from typing import Any, Iterable, Optional


def check_int(name: str, value: Any, minimum: int = 1, maximum: Optional[int] = None) -> int:
    """`value` as a Python int, checked to lie in minimum..maximum (no upper bound when None).

    Raises:
        ValueError: not an int (bools included), or out of range.
    """
    bounds = f"in {minimum}..{maximum}" if maximum is not None else f">= {minimum}"
    if isinstance(value, bool):
        raise ValueError(f"{name} must be an int {bounds}, got {value!r}")
    try:
        number = operator.index(value)
    except TypeError:
        raise ValueError(f"{name} must be an int {bounds}, got {value!r}") from None
    if number < minimum or (maximum is not None and number > maximum):
        raise ValueError(f"{name} must be an int {bounds}, got {value!r}")
    return number


def check_bool(name: str, value: Any) -> bool:
    """`value`, which must be True or False (not 0, 1 or "yes").

    Raises:
        ValueError: anything else.
    """
    if not isinstance(value, bool):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return value


def check_probability(name: str, value: Any) -> float:
    """`value` as a float in [0, 1].

    Raises:
        ValueError: not a real number, or outside [0, 1].
    """
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number in [0, 1], got {value!r}") from None
    if isinstance(value, bool) or not 0.0 <= number <= 1.0:
        raise ValueError(f"{name} must be a number in [0, 1], got {value!r}")
    return number


def check_choice(name: str, value: Any, choices: Iterable[Any]) -> Any:
    """`value`, which must be one of `choices`.

    Raises:
        ValueError: anything else; the message lists the choices.
    """
    choices = tuple(choices)
    if isinstance(value, bool) or value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}")
    return value
