"""CHIP-8, SUPER-CHIP and XO-CHIP program images: validation and loading.

A `Rom` is plain bytes plus a name; it never touches JAX. Bad input fails here, early, with a
message that says what was wrong, instead of surfacing later as a silently truncated program.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
from pathlib import Path
from typing import Optional, Union

PROGRAM_ADDRESS = 0x200
MEMORY_SIZE = 0x1000
MAX_ROM_SIZE = MEMORY_SIZE - PROGRAM_ADDRESS  # 3584 bytes: CHIP-8 and SUPER-CHIP
MAX_XOCHIP_ROM_SIZE = 0x10000 - PROGRAM_ADDRESS  # 65024 bytes: XO-CHIP's 64 KiB

RomLike = Union["Rom", bytes, bytearray, memoryview, str, os.PathLike]


class RomTooLargeError(ValueError):
    """A program larger than any platform holds: more than 65024 bytes (XO-CHIP's 64 KiB, loaded
    at 0x200). A `ValueError`, as every other refused ROM."""


def _too_large(name: str, size: Optional[int]) -> str:
    told = f"{size} bytes" if size is not None else f"more than {MAX_XOCHIP_ROM_SIZE} bytes"
    return (f"ROM {name!r} is {told}; a program loaded at 0x200 holds at most "
            f"{MAX_ROM_SIZE} bytes on chip8 and schip, {MAX_XOCHIP_ROM_SIZE} on xochip")


def read_rom_file(path: Union[str, os.PathLike]) -> bytes:
    """The bytes of the ROM file at `path`, reading at most one byte more than any platform holds.

    Every ROM that comes from a path the user gave (`Rom.load`, a game's ROM through the ROM
    store) is read here. A path can name anything: a 1 GiB file given as a ROM used to be read
    whole, into memory, before it was refused; now the read stops at 65025 bytes.

    Raises:
        RomTooLargeError: the file holds more than 65024 bytes; the message gives its size and
            the limit of each platform.
        OSError: the file cannot be opened or read.
    """
    with open(path, "rb") as file:
        data = file.read(MAX_XOCHIP_ROM_SIZE + 1)
        if len(data) > MAX_XOCHIP_ROM_SIZE:
            size = os.fstat(file.fileno()).st_size  # 0 for a device or pipe: size unknown
            raise RomTooLargeError(_too_large(Path(path).name, size if size > MAX_XOCHIP_ROM_SIZE else None))
    return data


@dataclasses.dataclass(frozen=True)
class Rom:
    """A validated program image.

    Args:
        data: the program bytes, loaded at 0x200; 1 to 65024 bytes (XO-CHIP's 64 KiB; a CHIP-8
            or SUPER-CHIP machine takes at most 3584, which `Machine.boot` checks).
        name: a label for messages and listings.

    Raises:
        TypeError: `data` is not bytes-like.
        ValueError: `data` is empty; `RomTooLargeError` (a ValueError) when it is longer than
            65024 bytes.
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
            raise RomTooLargeError(_too_large(self.name, len(data)))

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
            ValueError: the program is empty; `RomTooLargeError` (a ValueError) when it is too
                large, raised after reading at most 65025 bytes of a file.
        """
        if isinstance(rom, Rom):
            return rom
        if isinstance(rom, (bytes, bytearray, memoryview)):
            return cls(bytes(rom))
        if isinstance(rom, (str, os.PathLike)):
            path = Path(rom)
            if not path.is_file():
                raise FileNotFoundError(f"no ROM file at {str(path)!r}")
            return cls(read_rom_file(path), name=path.name)
        raise TypeError(
            f"a ROM must be a Rom, bytes or a file path, got {type(rom).__name__}"
        )
