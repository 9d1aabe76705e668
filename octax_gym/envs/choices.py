"""The one error for a name outside a fixed set of choices, and the check that raises it.

A game, policy, backend, render mode, palette, device, autoreset mode or option name that is not
one of the valid ones raises `UnknownOptionError` wherever it is given, with one wording:
"unknown policy 'greedy'; valid: None, 'random', 'noop', or a function ...", and, for a near
miss, the close matches first ("unknown game 'Pongg' (did you mean 'Pong'?); valid: ...").

It is a ValueError, what these checks raised before and what callers catch for a bad argument,
and a KeyError too: unknown game ids were the core registry's KeyError (`octax_core.get_spec`),
and code that catches that still catches the resolver's error.
"""

from __future__ import annotations

import difflib
from typing import Any, Iterable, Optional

MAX_SUGGESTIONS = 3  # close matches named in a message


class UnknownOptionError(ValueError, KeyError):
    """A value outside its valid choices; the message names it and every valid choice.

    Attributes:
        what: what was looked up ("game", "policy", "reset option(s)").
        value: what was given (a list of names for several unknown keys).
        choices: the valid values.
        also: what else is valid that is not a value of `choices` ("or a function ...").

    `near`, when given, holds the names to suggest from instead of `choices` (a game's
    Gymnasium ids too, which the message does not list).
    """

    def __init__(self, what: str, value: Any, choices: Iterable[Any], also: str = "",
                 near: Optional[Iterable[str]] = None):
        self.what, self.value, self.choices, self.also = what, value, tuple(choices), also
        suggestions = _suggestions(value, self.choices if near is None else tuple(near))
        super().__init__(_message(what, value, self.choices, also, suggestions))

    def __str__(self) -> str:
        return ValueError.__str__(self)  # not KeyError's, which would print the message as a repr


def check_choice(what: str, value: Any, choices: Iterable[Any], also: str = "") -> Any:
    """`value`, when it is one of `choices` (True and False never are: 1 == True in Python).

    Raises:
        UnknownOptionError: anything else.
    """
    choices = tuple(choices)
    if isinstance(value, bool) or not _is_one_of(value, choices):
        raise UnknownOptionError(what, value, choices, also)
    return value


def check_names(what: str, names: Iterable[str], valid: Iterable[str]) -> None:
    """Checks that every name of a set of keys is valid (options dicts, keyword sets).

    Raises:
        UnknownOptionError: some are not; the message lists them, sorted, and the valid ones.
    """
    valid = tuple(valid)
    unknown = sorted(set(names) - set(valid))
    if unknown:
        raise UnknownOptionError(what, unknown, valid)


def _is_one_of(value: Any, choices: tuple) -> bool:
    try:
        return value in choices
    except (TypeError, ValueError):  # e.g. a numpy array, whose == gives an array
        return False


def _message(what: str, value: Any, choices: tuple, also: str, hint: str) -> str:
    listing = ", ".join(map(repr, choices))
    if also:
        listing = f"{listing}, {also}" if listing else also
    return f"unknown {what} {value!r}{f' (did you mean {hint}?)' if hint else ''}; valid: {listing}"


def _suggestions(value: Any, choices: tuple) -> str:
    """The valid names closest to each given name ('Pong' for 'pong' or 'Pongg'), or ''."""
    names = [choice for choice in choices if isinstance(choice, str)]
    given = value if isinstance(value, list) else [value]
    lowered = {name.lower(): name for name in names}
    close: list[str] = []
    for text in (item for item in given if isinstance(item, str)):
        matches = difflib.get_close_matches(text.lower(), list(lowered), n=MAX_SUGGESTIONS, cutoff=0.75)
        close += [lowered[match] for match in matches if lowered[match] not in close]
    return " or ".join(map(repr, close[:MAX_SUGGESTIONS]))
