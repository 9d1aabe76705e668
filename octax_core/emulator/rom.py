"""CHIP-8, SUPER-CHIP and XO-CHIP program images: validation and loading.

A `Rom` is plain bytes plus a name; it never touches JAX. Bad input fails here, early, with a
message that says what was wrong, instead of surfacing later as a silently truncated program.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
from pathlib import Path
from typing import Union

PROGRAM_ADDRESS = 0x200
MEMORY_SIZE = 0x1000
MAX_ROM_SIZE = MEMORY_SIZE - PROGRAM_ADDRESS  # 3584 bytes: CHIP-8 and SUPER-CHIP
MAX_XOCHIP_ROM_SIZE = 0x10000 - PROGRAM_ADDRESS  # 65024 bytes: XO-CHIP's 64 KiB

RomLike = Union["Rom", bytes, bytearray, memoryview, str, os.PathLike]


@dataclasses.dataclass(frozen=True)
class Rom:
    """A validated program image.

    Args:
        data: the program bytes, loaded at 0x200; 1 to 65024 bytes (XO-CHIP's 64 KiB; a CHIP-8
            or SUPER-CHIP machine takes at most 3584, which `Machine.boot` checks).
        name: a label for messages and listings.

    Raises:
        TypeError: `data` is not bytes-like.
        ValueError: `data` is empty or longer than 65024 bytes.
    """

    data: bytes
    name: str = "<bytes>"

    def __post_init__(self):
        if not isinstance(self.data, (bytes, bytearray, memoryview)):
            raise TypeError(
                f"ROM data must be bytes, bytearray or memoryview, got {type(self.data).__name__}"
            )
        data = bytes(self.data)
        object.__setattr__(self, "data", data)
        if not data:
            raise ValueError(f"ROM {self.name!r} is empty: a CHIP-8 program needs at least 1 byte")
        if len(data) > MAX_XOCHIP_ROM_SIZE:
            raise ValueError(
                f"ROM {self.name!r} is {len(data)} bytes; a program loaded at 0x200 holds at most "
                f"{MAX_ROM_SIZE} bytes on chip8 and schip, {MAX_XOCHIP_ROM_SIZE} on xochip"
            )

    @property
    def sha1(self) -> str:
        """Hex SHA-1 of the program bytes, as the community CHIP-8 database lists them."""
        return hashlib.sha1(self.data).hexdigest()

    @classmethod
    def load(cls, rom: RomLike) -> "Rom":
        """Turns a `Rom`, bytes or a file path into a validated `Rom`.

        Raises:
            TypeError: `rom` is none of those.
            FileNotFoundError: the path does not exist.
            ValueError: the program is empty or too large.
        """
        if isinstance(rom, Rom):
            return rom
        if isinstance(rom, (bytes, bytearray, memoryview)):
            return cls(bytes(rom))
        if isinstance(rom, (str, os.PathLike)):
            path = Path(rom)
            if not path.is_file():
                raise FileNotFoundError(f"no ROM file at {str(path)!r}")
            return cls(path.read_bytes(), name=path.name)
        raise TypeError(
            f"a ROM must be a Rom, bytes or a file path, got {type(rom).__name__}"
        )
