"""The three machines: CHIP-8, SUPER-CHIP and XO-CHIP, as static config.

A platform fixes the instruction set, the memory size and the display; the quirks (how the
ambiguous instructions behave) are a separate choice, and any platform may run with any quirks.
Like the quirks, the platform shapes the traced program, so it lives in the frozen `Machine`,
never in the state. Each platform is a superset of the one before: an opcode introduced by a
later platform is an unknown opcode (a no-op) on an earlier one.
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
    """

    name: str
    level: int
    memory_size: int
    planes: int
    default_quirks: str

    @property
    def extended(self) -> bool:
        """Whether this is SUPER-CHIP or later: the 128x64 display, flags, exit."""
        return self.level > 0

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


PLATFORMS: dict[str, Platform] = {
    "chip8": Platform("chip8", 0, 0x1000, 0, "chip8"),
    "schip": Platform("schip", 1, 0x1000, 1, "schip"),
    "xochip": Platform("xochip", 2, 0x10000, 2, "xochip"),
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
