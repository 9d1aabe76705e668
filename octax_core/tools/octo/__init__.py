"""Octo, John Earnest's assembly language for CHIP-8, SUPER-CHIP and XO-CHIP: an assembler and a
disassembler.

`assemble(source) -> bytes` builds a program byte for byte as Octo does; `disassemble(rom) -> str`
turns a ROM back into Octo source that assembles to the same bytes. See docs/octo.md.
"""

from octax_core.tools.octo.assembler import Program, assemble, assemble_program
from octax_core.tools.octo.errors import AssemblyError

__all__ = ["AssemblyError", "Program", "assemble", "assemble_program", "disassemble"]


def __getattr__(name):
    # The disassembler is imported on first use, so the assembler works on its own.
    if name == "disassemble":
        from octax_core.tools.octo.disassembler import disassemble
        return disassemble
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
