"""`disassemble`: a CHIP-8 ROM back to Octo source that assembles to the very same bytes.

The source is meant to be read and edited, so code and data are told apart by following the
program's flow from 0x200 (jumps, calls, both sides of every skip; `jump0` and `return` end a
path): words reached that way become Octo statements, everything else becomes byte rows. The one
hard promise is the round trip: `assemble(disassemble(rom)) == rom` for every ROM, byte for byte.
That is why a few choices look fussy:

- Only encodings that Octo writes back unchanged are statements; the rest (5XY1, 8XY8, ...) stay
  bytes. A word that would run past the end of the ROM is data too.
- A target that is not the start of a statement or byte (the middle of an instruction, outside
  the ROM) is written as a number; every other target gets a label naming the address.
- Octo puts `jump main` at 0x200 by itself unless `: main` is the first thing in the program. A ROM
  that starts with a jump forward uses that trampoline (its target is `main`); any other ROM
  starts with `: main`, which turns the trampoline off, and is then written out from 0x200.
"""

from __future__ import annotations

import dataclasses

from octax_core.emulator.opcodes import Flow, lookup
from octax_core.emulator.rom import MAX_ROM_SIZE, PROGRAM_ADDRESS, Rom, RomLike


_LABEL_PREFIX = {Flow.CALL: "sub", Flow.JUMP: "loc", Flow.JUMP0: "table", Flow.INDEX: "data"}
_PICTURE_MAX = 32  # data runs up to this long (a 16x16 sprite) are drawn one byte a line
_PIXELS = str.maketrans("01", ".#")


@dataclasses.dataclass(frozen=True)
class Instruction:
    """One decoded instruction: where it is, its bytes, its Octo template and flow."""

    address: int
    size: int  # 2, or 4 for `i := long`
    template: str
    flow: Flow
    fields: dict  # format fields for `template`, except `target`
    target: int | None  # the address operand of jump, call, jump0 and i :=

    def successors(self, rom: bytes) -> list[int]:
        """The addresses execution can reach next (skips land 4 bytes on past an `i := long`)."""
        after = self.address + self.size
        if self.flow in (Flow.NEXT, Flow.INDEX):
            return [after]
        if self.flow is Flow.CALL:
            return [self.target, after]
        if self.flow is Flow.JUMP:
            return [self.target]
        if self.flow is Flow.SKIP:
            skipped = decode(rom, after)
            return [after, after + (skipped.size if skipped else 2)]
        return []

    def statement(self, labels: dict[int, str] | None = None) -> str:
        """The Octo statement, naming the target by its label if `labels` has one.

        A target without a label is written as a number, and a call to one as `:call NNN`
        (a bare number would be a data byte).
        """
        labels = labels or {}
        if self.target is None:
            return self.template.format(**self.fields)
        if self.target in labels:
            return self.template.format(target=labels[self.target], **self.fields)
        number = f"0x{self.target:04X}" if self.size == 4 else f"0x{self.target:03X}"
        if self.flow is Flow.CALL:
            return f":call {number}"
        return self.template.format(target=number, **self.fields)


def decode(rom: bytes, address: int) -> Instruction | None:
    """The instruction at `address`, or None if the word there is no statement Octo writes back."""
    offset = address - PROGRAM_ADDRESS
    if offset < 0 or offset + 2 > len(rom):
        return None
    word = rom[offset] << 8 | rom[offset + 1]
    row = lookup(word)  # the opcode table the emulator decodes with too
    if row is None or row.octo is None:
        return None
    template, flow = row.octo, row.flow
    x, y = word >> 8 & 0xF, word >> 4 & 0xF
    fields = {"x": f"v{x:x}", "y": f"v{y:x}", "xn": x, "n": word & 0xF, "nn": f"0x{word & 0xFF:02X}",
              "nnn": f"0x{word & 0xFFF:03X}"}
    if word == 0xF000:
        if offset + 4 > len(rom):
            return None
        return Instruction(address, 4, template, flow, fields, rom[offset + 2] << 8 | rom[offset + 3])
    target = word & 0xFFF if "{target}" in template else None
    return Instruction(address, 2, template, flow, fields, target)


def disassemble(rom: RomLike) -> str:
    """Octo source for a CHIP-8 program that `assemble` turns back into exactly the same bytes.

    Args:
        rom: the program (loaded at 0x200): bytes, a `Rom`, or the path of a .ch8 file. Empty
            bytes are allowed and give a program that assembles to nothing.

    Returns:
        The Octo source: labels named after their address (`sub-2A4` for calls, `loc-` for jumps,
        `table-` for jump0, `data-` for i :=), statements for the code reached from 0x200, byte
        rows for the rest.

    Raises:
        TypeError: `rom` is none of those types.
        ValueError: the program is longer than 3584 bytes.
        FileNotFoundError: no file at that path.
    """
    data = _rom_bytes(rom)
    code = _layout(data, reachable_instructions(data))
    trampoline = _trampoline_target(data, code)
    labels = _labels(data, code, trampoline)
    return _render(data, code, labels, trampoline)


def _rom_bytes(rom: RomLike) -> bytes:
    if isinstance(rom, (bytes, bytearray, memoryview)):
        data = bytes(rom)
        if len(data) > MAX_ROM_SIZE:
            raise ValueError(f"a CHIP-8 program holds at most {MAX_ROM_SIZE} bytes, got {len(data)}")
        return data
    return Rom.load(rom).data


def reachable_instructions(rom: bytes) -> dict[int, Instruction]:
    """Every instruction that execution from 0x200 can reach, by address (they may overlap).

    The code/data split of the disassembly, and the static half of `octax-gym trace`
    (`octax_core.tools.rom_scan`), which must never read sprite bytes as instructions.
    """
    found: dict[int, Instruction] = {}
    pending = [PROGRAM_ADDRESS]
    while pending:
        address = pending.pop()
        if address in found:
            continue
        instruction = decode(rom, address)
        if instruction is not None:
            found[address] = instruction
            pending.extend(instruction.successors(rom))
    return found


def _layout(rom: bytes, reachable: dict[int, Instruction]) -> dict[int, Instruction]:
    """The instructions written as statements: reachable ones that overlap no earlier one.

    Every other byte is data. When two reachable instructions overlap (a jump into the middle of
    another), the earlier one wins and the later one's address is referred to as a number.
    """
    code: dict[int, Instruction] = {}
    address, end = PROGRAM_ADDRESS, PROGRAM_ADDRESS + len(rom)
    while address < end:
        instruction = reachable.get(address)
        if instruction is None:
            address += 1
        else:
            code[address] = instruction
            address += instruction.size
    return code


def _line_starts(rom: bytes, code: dict[int, Instruction]) -> set[int]:
    """Addresses a label can be put at: each statement's first byte, and every data byte."""
    inside = {a + k for a, ins in code.items() for k in range(1, ins.size)}
    return set(range(PROGRAM_ADDRESS, PROGRAM_ADDRESS + len(rom))) - inside


def _trampoline_target(rom: bytes, code: dict[int, Instruction]) -> int | None:
    """Where the ROM's opening `jump` goes, if Octo's own `jump main` at 0x200 can stand for it.

    Octo drops that jump when `main` is at 0x202, and `main` must be a place a label can go.
    """
    first = code.get(PROGRAM_ADDRESS)
    if first is None or first.flow is not Flow.JUMP:
        return None
    target = first.target
    if target <= PROGRAM_ADDRESS + 2 or target not in _line_starts(rom, code):
        return None
    return target


def _labels(rom: bytes, code: dict[int, Instruction], trampoline: int | None) -> dict[int, str]:
    """A name for each target that a label can mark; the first program byte is always `main`."""
    starts = _line_starts(rom, code)
    if trampoline is not None:
        starts.discard(PROGRAM_ADDRESS)  # written by Octo itself: no label can go there
    labels = {trampoline if trampoline is not None else PROGRAM_ADDRESS: "main"}
    for flow, prefix in _LABEL_PREFIX.items():  # calls name a target first, then jumps, then i :=
        for instruction in code.values():
            target = instruction.target
            if instruction.flow is flow and target in starts and target not in labels:
                labels[target] = f"{prefix}-{target:03X}"
    return labels


def _render(rom: bytes, code: dict[int, Instruction], labels: dict[int, str],
            trampoline: int | None) -> str:
    lines = [f"# Disassembled by octax_core.tools.octo.disassemble: {len(rom)} bytes at 0x200."]
    if trampoline is None:
        lines.append(": main  # first, so Octo adds no `jump main` of its own")
        start = PROGRAM_ADDRESS
    else:
        lines.append("# 0x200: `jump main`, which Octo writes itself")
        start = PROGRAM_ADDRESS + 2
    address, end, indent = start, PROGRAM_ADDRESS + len(rom), "\t"
    while address < end:
        if address in labels and not (address == PROGRAM_ADDRESS and trampoline is None):
            lines += ["", f": {labels[address]}"]  # (`: main` at 0x200 is already written)
        instruction = code.get(address)
        if instruction is not None:
            lines.append(indent + instruction.statement(labels))
            indent = "\t\t" if instruction.flow is Flow.SKIP else "\t"
            address += instruction.size
            continue
        run_end = _data_run_end(address, end, code, labels)
        lines += _data_lines(rom, address, run_end, labels.get(address, "").startswith("data-"))
        address, indent = run_end, "\t"
    return "\n".join(lines) + "\n"


def _data_run_end(address: int, end: int, code: dict[int, Instruction], labels: dict[int, str]) -> int:
    """Where the bytes from `address` stop: at the next statement, label or the end of the ROM."""
    address += 1
    while address < end and address not in code and address not in labels:
        address += 1
    return address


def _data_lines(rom: bytes, start: int, stop: int, sprite: bool) -> list[str]:
    """Byte rows; short runs that `i :=` points at are drawn one byte a line, as sprites."""
    values = rom[start - PROGRAM_ADDRESS:stop - PROGRAM_ADDRESS]
    if sprite and len(values) <= _PICTURE_MAX:
        return [f"\t0x{v:02X}  # {format(v, '08b').translate(_PIXELS)}" for v in values]
    return [f"\t{' '.join(f'0x{v:02X}' for v in values[k:k + 8])}  # 0x{start + k:03X}"
            for k in range(0, len(values), 8)]
