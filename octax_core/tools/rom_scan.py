"""What a ROM's code does with each register, read without running it: the static half of the
ranking in `octax_core.tools.trace_rank`.

The paper's static analysis looks for FX33 (BCD: store a number's decimal digits, to draw them),
which marks a number shown on screen, often the score. Only code reachable from 0x200 is read
(`reachable_code`), so sprite and map bytes that happen to look like FX33 never count, and an
instruction at an odd address, after an odd-sized block of data, is still found.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from octax_core.tools.octo.disassembler import reachable_instructions
from octax_core.emulator.rom import PROGRAM_ADDRESS

NUM_REGISTERS = 16


@dataclasses.dataclass(frozen=True)
class RomFacts:
    """What the reachable code of a ROM does with each register (16 bools each)."""

    bcd: np.ndarray  # shown as a decimal number: FX33, or copied by 8XY0 into the FX33 register
    digit: np.ndarray  # shown as one hex digit: FX29
    decremented: np.ndarray  # 7XFF (ADD VX, -1)
    tested_zero: np.ndarray  # 3X00 / 4X00 (skip if VX == 0 / != 0)


def rom_facts(rom: bytes) -> RomFacts:
    """Register uses in the ROM's reachable code (`reachable_code`), for the static features."""
    memory = bytes(PROGRAM_ADDRESS) + bytes(rom)
    flags = {name: np.zeros(NUM_REGISTERS, bool) for name in ("bcd", "digit", "decremented", "tested_zero")}
    code = set(reachable_code(rom))
    for address in code:
        op = memory[address] << 8 | memory[address + 1]
        x = op >> 8 & 0xF
        if op & 0xF0FF == 0xF033:
            flags["bcd"][x] = True
            before = memory[address - 2] << 8 | memory[address - 1]
            if address - 2 in code and before & 0xF00F == 0x8000 and (before >> 8 & 0xF) == x:
                flags["bcd"][before >> 4 & 0xF] = True  # VX := VY; bcd VX: the number shown is VY's
        elif op & 0xF0FF == 0xF029:
            flags["digit"][x] = True
        elif op & 0xF0FF == 0x70FF:
            flags["decremented"][x] = True
        elif op >> 12 in (0x3, 0x4) and op & 0xFF == 0:
            flags["tested_zero"][x] = True
    return RomFacts(**flags)


def reachable_code(rom: bytes) -> list[int]:
    """Addresses of the instructions reachable from 0x200, following jumps, calls and skips.

    The disassembler's flow analysis (`reachable_instructions`): data between routines (sprites,
    maps) is never decoded, an FX33 at an odd address is still found, and BNNN (a computed jump),
    `return` and words that are no instruction end a path.
    """
    return sorted(reachable_instructions(bytes(rom)))
