"""A ROM file is read only as far as the largest program any platform holds, plus one byte
(issue 38, item 8): a 1 GiB file given as a ROM used to be read whole before it was refused.

The big files here are sparse (`truncate`), so they take no disk; what the tests measure is the
memory Python allocates while refusing them, which a whole read would make 1 GiB.
"""

from __future__ import annotations

import dataclasses
import hashlib
import tracemalloc

import pytest

from octax_core import Rom
from octax_core.emulator.rom import MAX_XOCHIP_ROM_SIZE, RomTooLargeError, read_rom_file
from octax_core.env import romstore

GIB = 1 << 30
SMALL = 1 << 20  # far more than the 65025 bytes read, far less than the file


def _sparse(path, size: int):
    with open(path, "wb") as file:
        file.truncate(size)
    return path


def _peak_bytes(function) -> int:
    """The most memory Python held while `function` ran (its exception is the caller's)."""
    tracemalloc.start()
    try:
        function()
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak


@dataclasses.dataclass(frozen=True)
class _Spec:
    id: str = "toy"
    rom_file: str = "toy.ch8"
    rom_sha1: str = "0" * 40


def test_a_1_gib_rom_file_is_refused_after_reading_65025_bytes(tmp_path):
    big = _sparse(tmp_path / "big.ch8", GIB)
    caught = []

    def load():
        with pytest.raises(RomTooLargeError) as error:
            Rom.load(big)
        caught.append(error.value)

    assert _peak_bytes(load) < SMALL
    message = str(caught[0])
    assert "'big.ch8' is 1073741824 bytes" in message
    assert "at most 3584 bytes on chip8 and schip, 65024 on xochip" in message
    assert isinstance(caught[0], ValueError)  # callers that catch ValueError still do


def test_the_limit_is_the_largest_program(tmp_path):
    fits = tmp_path / "fits.xo8"
    fits.write_bytes(bytes(MAX_XOCHIP_ROM_SIZE))
    assert len(Rom.load(fits).data) == MAX_XOCHIP_ROM_SIZE
    over = tmp_path / "over.xo8"
    over.write_bytes(bytes(MAX_XOCHIP_ROM_SIZE + 1))
    with pytest.raises(RomTooLargeError, match="'over.xo8' is 65025 bytes"):
        read_rom_file(over)


def test_a_games_rom_path_is_refused_the_same_way(tmp_path):
    # Before, the ROM store read the whole file to hash it, then said "SHA-1 is ..., expected ...".
    big = _sparse(tmp_path / "toy.ch8", GIB)

    def load():
        with pytest.raises(RomTooLargeError, match="'toy.ch8' is 1073741824 bytes"):
            romstore.load_game_rom(_Spec(), big)

    assert _peak_bytes(load) < SMALL


def test_rom_status_hashes_a_big_file_without_holding_it(tmp_path, monkeypatch):
    size = 64 << 20
    _sparse(tmp_path / "toy.ch8", size)
    monkeypatch.setenv("OCTAX_ROM_DIR", str(tmp_path))
    rows = []
    assert _peak_bytes(lambda: rows.extend(romstore.rom_status([_Spec()]))) < 4 * SMALL
    assert not rows[0].verified
    assert rows[0].actual_sha1 == hashlib.sha1(bytes(size)).hexdigest()


def test_the_command_line_names_the_limit(tmp_path, capsys):
    from octax_gym.cli import main

    big = _sparse(tmp_path / "big.ch8", GIB)
    status = []
    assert _peak_bytes(lambda: status.append(main(["disasm", str(big)]))) < 4 * SMALL
    assert status == [1]
    error = capsys.readouterr().err
    assert error.startswith("octax-gym: error: ROM 'big.ch8' is 1073741824 bytes; ")
    assert "65024 on xochip" in error
