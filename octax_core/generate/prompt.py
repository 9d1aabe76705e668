"""The paper's prompt (octax, appendix "Prompt Engineering"), and the parts that fill it.

The template is the paper's, word for word, with its four reference tags (`<documentation>`:
the Octo manual, `<tutorial1>` and `<tutorial2>`: the beginner's and intermediate guides,
`<example>`: a complete game). Those documents are John Earnest's and are not shipped here: name
them by path (`octax-gym generate --prompt-part documentation=Manual.md ...`). The example
defaults to one of our own games, a dodger variant rendered from its family template. One
paragraph is added after the description (`REGISTERS_REQUEST`): the registers stated in a form
the loop reads back (`octax_core.generate.llm.stated_registers`), to be checked against the tracer.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Optional

PARTS = ("documentation", "tutorial1", "tutorial2", "example")

TEMPLATE = """You are a **professional CHIP-8 (classic version) game developer**.
Your task is to **design and implement new CHIP-8 games in Octo assembly language**. I will provide you with tutorials and references for Octo assembly. You must be rigorous and ensure that your code is **syntactically correct, runnable, and follows CHIP-8 conventions**.

<documentation>{documentation}</documentation>

<tutorial1>{tutorial1}</tutorial1>

<tutorial2>{tutorial2}</tutorial2>

<example>{example}</example>

The goal is to create a **game suitable for reinforcement learning (RL) research**, which means:
* The **score** must be stored in a clear and consistent register or memory location.
* The **termination condition** (game over) must also be easily extractable (e.g., through a specific flag or register value).
* The game should have **deterministic rules** and be lightweight enough for training agents.

Here is the description of the game you must implement:

<description>{description}</description>
"""

REGISTERS_REQUEST = """
Answer with the whole program in one fenced code block. After it, state the registers on lines of
this form (the keys are the CHIP-8 keys the player uses):
score: vN
game over: vN == K
lives: vN (or: lives: none)
keys: 4 6
"""


def default_example() -> str:
    """A dodger variant's source: one of our own games, to show the idioms the paper's example shows."""
    from octax_core.generate.families import get_family
    from octax_core.generate.render import render
    from octax_core.generate.sample import sample_params

    family = get_family("dodger")
    return render(family, sample_params(family, 0, 0))


def read_parts(paths: Mapping[str, str]) -> dict:
    """{part: text} from {part: path}; ValueError names an unknown part or a file it cannot read."""
    parts = {}
    for name, path in paths.items():
        if name not in PARTS:
            raise ValueError(f"unknown prompt part {name!r}; valid: {', '.join(PARTS)}")
        try:
            parts[name] = Path(path).expanduser().read_text(encoding="utf-8")
        except OSError as exc:
            raise ValueError(f"prompt part {name}: cannot read {path}: {exc.strerror}") from None
    return parts


def build_prompt(description: str, parts: Optional[Mapping[str, str]] = None) -> str:
    """The first message: the template with `parts` (a missing part is left empty, but the
    example, which defaults to `default_example()`), the description and the registers request."""
    if not description.strip():
        raise ValueError("a game description must not be empty")
    filled = {name: "" for name in PARTS}
    filled["example"] = default_example()
    filled.update(parts or {})
    return TEMPLATE.format(description=description, **filled) + REGISTERS_REQUEST
