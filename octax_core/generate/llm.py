"""The paper's LLM loop: a description in, an Octo program out, repaired from the assembler's
messages, its score and end taken from the reply and checked against the register tracer.

    for each description:
        ask (the paper's prompt, `octax_core.generate.prompt`)
        up to `repairs` times: the reply's program does not assemble -> send back the message
            (line, column, what was expected, the line with a caret) and ask for the whole program
        the registers: as the reply states them (`score: vN`, `game over: vN == K`, ...), checked
            against the tracer's ranking; where it states none, the tracer's best candidates

The result is a `rounds.Candidate`, judged by the same filters as a family's variants. `ask` is
any function of the message list that returns the reply's text (`chat.complete` bound to a
server, or a test's stand-in).
"""

from __future__ import annotations

import hashlib
import re
import tempfile
from pathlib import Path
from typing import Callable, Mapping, Optional, Sequence

from octax_core.generate.rounds import Candidate
from octax_core.tools.octo import AssemblyError, assemble

FENCE = re.compile(r"```[^\n`]*\n(.*?)```", re.DOTALL)
_REG = r"\bv([0-9a-e])\b"
SCORE_LINE = re.compile(r"^\W*score\b[^\n]*?" + _REG, re.IGNORECASE | re.MULTILINE)
END_LINE = re.compile(r"^\W*(?:game[ -]?over|termination|end)\b[^\n]*?" + _REG + r"(?:\s*==\s*(0x[0-9a-f]+|\d+))?",
                      re.IGNORECASE | re.MULTILINE)
LIVES_LINE = re.compile(r"^\W*lives\b[^\n]*?(?:" + _REG + r"|\bnone\b)", re.IGNORECASE | re.MULTILINE)
KEYS_LINE = re.compile(r"^\W*keys?\s*:\s*([0-9a-f](?:[\s,]+[0-9a-f])*)\s*$", re.IGNORECASE | re.MULTILINE)
TRACE_STEPS = 1500

Ask = Callable[[Sequence[dict]], str]


def program_of(reply: str) -> str:
    """The reply's first fenced code block, or the whole reply where it has none."""
    match = FENCE.search(reply)
    return match.group(1) if match else reply


def stated_registers(reply: str) -> dict:
    """What the reply says of the registers, as far as it says: {"score": 5, "end": [14, 1],
    "lives": 6 or None, "keys": [4, 6]}; absent keys were not stated. Searched outside the
    program (a comment in it may name a register for some other role)."""
    text = FENCE.sub("", reply)
    found = {}
    if match := SCORE_LINE.search(text):
        found["score"] = int(match.group(1), 16)
    if match := END_LINE.search(text):
        found["end"] = [int(match.group(1), 16), int(match.group(2), 0) if match.group(2) else 1]
    if match := LIVES_LINE.search(text):
        found["lives"] = int(match.group(1), 16) if match.group(1) else None
    if match := KEYS_LINE.search(text):
        keys = [int(k, 16) for k in re.split(r"[\s,]+", match.group(1).strip())]
        if len(set(keys)) == len(keys):
            found["keys"] = keys
    return found


def repair_message(error: AssemblyError) -> str:
    """The next turn after a program that does not assemble: the assembler's own words."""
    return (f"The program does not assemble. The Octo assembler says:\n{error}\n"
            "Fix it and answer with the whole corrected program in one fenced code block, "
            "then the registers as before.")


def converse(ask: Ask, first: str, repairs: int) -> tuple[list[dict], str, Optional[bytes], str]:
    """Asks, then repairs up to `repairs` times. Returns (messages, program, rom or None, the
    last assembler message or "")."""
    if repairs < 0:
        raise ValueError(f"repairs must be >= 0, got {repairs}")
    messages = [{"role": "user", "content": first}]
    for attempt in range(repairs + 1):
        reply = ask(messages)
        messages.append({"role": "assistant", "content": reply})
        program = program_of(reply)
        try:
            return messages, program, assemble(program), ""
        except AssemblyError as exc:
            if attempt == repairs:
                return messages, program, None, str(exc)
            messages.append({"role": "user", "content": repair_message(exc)})
    raise AssertionError("unreachable")


def traced_registers(rom: bytes, keys: Sequence[int], steps: int = TRACE_STEPS) -> dict:
    """The tracer's best candidates, told nothing (`octax_core.tools.trace`): {"score", "lives",
    "end": [register, 1]}; a game-over flag is taken to read 1 when set."""
    from octax_core.generate.build import variant_spec
    from octax_core.tools.trace import blind_spec, record_trace
    from octax_core.tools.trace_rank import rank_registers

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "game.ch8"
        path.write_bytes(rom)
        spec = blind_spec(variant_spec("traced", hashlib.sha1(rom).hexdigest(), keys))
        ranking = rank_registers(record_trace(spec, steps=steps, blind=True, rom=path))
    def best(candidates):  # VF is the carry flag, never a game's own register
        return next(c.register for c in candidates if c.register <= 14)
    return {"score": best(ranking.score), "lives": best(ranking.lives), "end": [best(ranking.game_over), 1]}


def registers_for(reply: str, rom: bytes, keys: Sequence[int], trace_steps: int = TRACE_STEPS) -> tuple[dict, str]:
    """(registers, how they were found): the reply's where it states score and end, noted as
    agreeing or not with the tracer's; else the tracer's."""
    stated = stated_registers(reply)
    traced = traced_registers(rom, keys, trace_steps)
    if "score" in stated and "end" in stated:
        registers = {"score": stated["score"], "lives": stated.get("lives"), "end": stated["end"]}
        disagree = [f"{role} V{traced[role] if role != 'end' else traced['end'][0]:X}"
                    for role in ("score", "end")
                    if (registers[role] if role != "end" else registers["end"][0])
                    != (traced[role] if role != "end" else traced["end"][0])]
        note = ("stated in the reply; the tracer agrees" if not disagree else
                "stated in the reply; the tracer ranks first: " + ", ".join(disagree))
        return registers, note
    return traced, "found by the tracer (the reply stated no score and end)"


def llm_candidate(ask: Ask, description: str, name: str, repairs: int, parts: Optional[Mapping[str, str]] = None,
                  model: str = "", trace_steps: int = TRACE_STEPS) -> Candidate:
    """One description through the loop, as a candidate for `rounds.judge`."""
    from octax_core.generate.prompt import build_prompt

    messages, program, rom, error = converse(ask, build_prompt(description, parts), repairs)
    turns = sum(message["role"] == "assistant" for message in messages)
    params = {"description": description, "model": model, "replies": turns}
    if rom is None:
        return Candidate(name, "llm", params, program, None, error=error)
    reply = messages[-1]["content"]
    keys = stated_registers(reply).get("keys", list(range(16)))
    registers, note = registers_for(reply, rom, keys, trace_steps)
    return Candidate(name, "llm", params, program, rom, action_keys=tuple(keys),
                     registers=registers, extra={"registers_found": note})
