"""The three machines: CHIP-8, SUPER-CHIP and XO-CHIP, as static data for the one CPU.

A platform fixes the instruction set, the memory size and the display; the quirks (how the
ambiguous instructions behave) are a separate choice, and any platform may run with any quirks.
Like the quirks, the platform shapes the traced program, so it lives in the frozen `Machine`,
never in the state. Each platform is a superset of the one before: an opcode introduced by a
later platform is an unknown opcode (a no-op) on an earlier one.

Everything the executor (`octax_core.emulator.cpu`) does differently per platform is read from
here: the opcodes it decodes (`level`), how many bytes it fetches (`fetch_bytes`), where
addresses wrap (`memory_size`), how much of RAM's start is mirrored after it (`mirrored_bytes`),
the bit planes and their grid (`planes`, `extended`), and whether N = 0 draws a 16x16 sprite.
CHIP-8 is the smallest case of each.

A platform also carries the XLA compile options its programs run fastest under
(`compiler_options`), measured per platform; they change how XLA:CPU lays out buffers, never
what a program computes, and the jitted steps of octax-gym pass them to `jax.jit`.
"""

from __future__ import annotations

import dataclasses
from typing import Union

from octax_core.emulator.rom import PROGRAM_ADDRESS


@dataclasses.dataclass(frozen=True)
class Platform:
    """One machine's fixed shape.

    Attributes:
        name: "chip8", "schip" or "xochip".
        level: 0, 1, 2: the platform runs the opcodes of every level up to its own.
        memory_size: bytes of RAM; every address wraps at this size.
        planes: bit planes of the 128x64 display (0 for CHIP-8's own 64x32 one-plane display).
        default_quirks: the quirk profile a `Machine` on this platform uses unless told.
        xla_options: (name, value) pairs of XLA debug options for compiling this platform's
            programs; `compiler_options` gives them as the dict `jax.jit` takes.
    """

    name: str
    level: int
    memory_size: int
    planes: int
    default_quirks: str
    xla_options: tuple[tuple[str, object], ...] = ()

    @property
    def compiler_options(self) -> dict[str, object]:
        """`jax.jit(..., compiler_options=...)` for this platform's programs.

        Why: XLA:CPU's default copy insertion copies most of the instruction loop's registers on
        every instruction; its region analysis proves those copies needless and drops them, a
        gain on every platform. SUPER-CHIP carries it since its rare work went under one gate:
        before, with a multi-thread pool, the copies let its independent kernels run side by
        side, and dropping them lost more than the copies cost (docs/machine-log.md has the
        numbers). As an `XLA_FLAGS` flag it would set every program in the process, so it rides
        here, per compile. It changes buffers, not results:
        tests/core_emulator/test_compiler_options.py compares every step with and without it.
        """
        return dict(self.xla_options)

    @property
    def extended(self) -> bool:
        """Whether this is SUPER-CHIP or later: the 128x64 display, flags, exit."""
        return self.level > 0

    @property
    def fetch_bytes(self) -> int:
        """Bytes read at pc: 4 on XO-CHIP, whose F000 NNNN is 4 bytes long (a skip jumps over
        all of it, so every instruction looks at the word after it), else the 2 of an opcode."""
        return 4 if self.level >= 2 else 2

    @property
    def address_mask(self) -> int:
        """I, pc and the stack wrap at the memory size: address & address_mask."""
        return self.memory_size - 1

    @property
    def mirrored_bytes(self) -> int:
        """How many bytes of RAM's start are kept again after its end, so that every read at an
        address (16 at I for CHIP-8's loads and sprites; 64 for SUPER-CHIP's 16x16 sprite on
        two planes) is one contiguous slice (`state.MEMORY_OFFSET`)."""
        return 64 if self.extended else 16

    @property
    def wide_sprites(self) -> bool:
        """Whether DXY0 draws a 16x16 sprite (SUPER-CHIP and later); on CHIP-8 it draws nothing."""
        return self.extended

    @property
    def max_program_size(self) -> int:
        """The largest program that fits between 0x200 and the end of memory."""
        return self.memory_size - PROGRAM_ADDRESS

    @property
    def screen_shape(self) -> tuple[int, ...]:
        """The shape of `snapshot(state)["screen"]`: (32, 64), (64, 128) or (2, 64, 128)."""
        if not self.extended:
            return (32, 64)
        return (64, 128) if self.planes == 1 else (self.planes, 64, 128)


# Region-analysis copy insertion (see `Platform.compiler_options`).
_FEWER_COPIES = (("xla_cpu_copy_insertion_use_region_analysis", True),)

PLATFORMS: dict[str, Platform] = {
    "chip8": Platform("chip8", 0, 0x1000, 0, "chip8", _FEWER_COPIES),
    "schip": Platform("schip", 1, 0x1000, 1, "schip", _FEWER_COPIES),
    "xochip": Platform("xochip", 2, 0x10000, 2, "xochip", _FEWER_COPIES),
}


def resolve_platform(platform: Union[str, Platform]) -> Platform:
    """The `Platform` for a name, or `platform` itself.

    Raises:
        ValueError: an unknown name; the message lists the valid ones.
        TypeError: neither a name nor a `Platform`.
    """
    if isinstance(platform, Platform):
        return platform
    if isinstance(platform, str):
        if platform not in PLATFORMS:
            valid = ", ".join(repr(name) for name in PLATFORMS)
            raise ValueError(f"unknown platform {platform!r}; valid platforms: {valid}")
        return PLATFORMS[platform]
    raise TypeError(f"platform must be a platform name or a Platform, got {type(platform).__name__}")


def check_program_fits(size: int, name: str, platform: Platform) -> None:
    """Raises ValueError, naming both sizes, when a `size`-byte program is too large for `platform`."""
    if size > platform.max_program_size:
        fits = [p.name for p in PLATFORMS.values() if size <= p.max_program_size]
        hint = f"; it fits on {', '.join(fits)}" if fits else ""
        raise ValueError(
            f"ROM {name!r} is {size} bytes; a {platform.name} program loaded at 0x200 holds at most "
            f"{platform.max_program_size} bytes{hint}"
        )
