"""The ROM store: find, verify and install the ROM each game names by SHA-1.

The octax suite's ROMs are never committed, so a game's `GameSpec` carries only a file name and
the SHA-1 of the bytes it was written against. Lookup order (the first file found decides):

1. an explicit path given by the caller;
2. each folder in `OCTAX_ROM_DIR` (an `os.pathsep`-separated list; relative entries are taken
   from the current directory);
3. the user data folder, `user_rom_dir()`;
4. the ROMs that ship inside the package, `PROJECT_ROM_DIR` (octax_core/env/roms/): our own games
   (links to roms/*.ch8, built from `.8o` source) and, in `archive/`, the Chip8 Community
   Archive's CC0 programs (`ARCHIVE_ROM_DIR`, with their programs.json and LICENSE.md). A wheel
   carries them as package data, so they are there wherever the package is installed.

A file whose hash differs is refused with `RomHashError`, never loaded and never skipped for a
later folder: a corrupted or edited ROM would silently change the game. `import_roms` and
`install_from_pypi` fill the user folder, matching files by hash, never by name. Pure stdlib; the
`octax-gym roms ...` commands (`octax_gym/cli/roms.py`) are a thin layer over this module.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from typing import Iterable, Iterator, Optional, Protocol, Sequence, Union

from octax_core.emulator.rom import Rom, read_rom_file

PathLike = Union[str, os.PathLike]

PROJECT_ROM_DIR = Path(__file__).resolve().parent / "roms"
ARCHIVE_ROM_DIR = PROJECT_ROM_DIR / "archive"
FIX_HINT = (
    "run `octax-gym roms install` (gets the octax==0.1.1 wheel from PyPI and installs its ROMs), "
    "or `octax-gym roms import PATH` (a folder, zip or wheel you have), "
    "or set OCTAX_ROM_DIR to a folder holding the file"
)
# Files bigger than this are never ROM candidates when importing: a CHIP-8 program is at most
# 3584 bytes (XO-CHIP 64 KiB), and this keeps `roms import ~` from hashing every large file.
MAX_CANDIDATE_BYTES = 64 * 1024


class RomNotFoundError(FileNotFoundError):
    """No ROM file for a game in any folder searched (or at the explicit path given)."""


class RomHashError(ValueError):
    """A ROM file exists but its SHA-1 is not the one the game expects; it is never loaded."""


class RomInstallError(RuntimeError):
    """`install_from_pypi` could not download the wheel (pip failed, timed out or is missing)."""


class RomSpec(Protocol):
    """What the store needs of a game: `GameSpec` satisfies it."""

    id: str
    rom_file: str
    rom_sha1: str


@dataclasses.dataclass(frozen=True)
class RomStatus:
    """One game's ROM as `rom_status` finds it (a row of `octax-gym roms list`).

    `path` is the file lookup would use (None: missing); `verified` is true when its SHA-1
    matches; `actual_sha1` is the file's hash when present.
    """

    game_id: str
    rom_file: str
    sha1: str
    path: Optional[Path]
    verified: bool
    actual_sha1: Optional[str] = None


@dataclasses.dataclass(frozen=True)
class ImportedRom:
    """One ROM that `import_roms` put in place.

    `action` is "installed" (new), "replaced" (a file with other bytes was there) or
    "unchanged" (the right bytes were already there). `source` is the file, or `archive:member`.
    """

    game_ids: tuple[str, ...]
    rom_file: str
    sha1: str
    source: str
    path: Path
    action: str


def sha1_hex(data: bytes) -> str:
    """Hex SHA-1 of `data` (as `Rom.sha1` and the `SHA1SUMS` manifests list it)."""
    return hashlib.sha1(data, usedforsecurity=False).hexdigest()


def user_rom_dir() -> Path:
    """The per-user ROM folder that `roms install` and `roms import` write to.

    `$OCTAX_DATA_DIR/roms` if set, else `$XDG_DATA_HOME/octax-gym/roms` (absolute values only, as
    the XDG spec says), else `~/.local/share/octax-gym/roms`; the same fallback on macOS and Windows.
    """
    data_dir = os.environ.get("OCTAX_DATA_DIR")
    if data_dir:
        return (Path(data_dir).expanduser() / "roms").resolve()
    xdg = os.environ.get("XDG_DATA_HOME")
    base = Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".local" / "share"
    return (base / "octax-gym" / "roms").resolve()


def search_dirs() -> list[Path]:
    """The folders searched for a game's ROM, in order (see the module docstring); no duplicates."""
    dirs = [Path(entry).expanduser().resolve()
            for entry in os.environ.get("OCTAX_ROM_DIR", "").split(os.pathsep) if entry]
    dirs.append(user_rom_dir())
    if PROJECT_ROM_DIR.is_dir():
        dirs.append(PROJECT_ROM_DIR)
    return list(dict.fromkeys(dirs))


def find_rom(spec: RomSpec, path: Optional[PathLike] = None) -> Path:
    """The verified ROM file for `spec`: `path` if given, else the first hit in `search_dirs()`.

    Args:
        spec: the game (`id`, `rom_file`, `rom_sha1`).
        path: a ROM file, or a folder holding `spec.rom_file`; skips the search.

    Returns:
        The path of a file whose SHA-1 is `spec.rom_sha1`.

    Raises:
        RomNotFoundError: no such file; the message names the game, file, hash and the fix.
        RomHashError: the file found has another SHA-1.
        RomTooLargeError: the file holds more than 65024 bytes (read no further than that).
    """
    return _locate_verified(spec, path)[0]


def load_game_rom(spec: RomSpec, path: Optional[PathLike] = None) -> Rom:
    """The game's `Rom`, read once and verified (same lookup and errors as `find_rom`)."""
    found, data = _locate_verified(spec, path)
    return Rom(data, name=found.name)


def rom_status(specs: Iterable[RomSpec]) -> list[RomStatus]:
    """Where each game's ROM is and whether its hash matches; never raises for a missing or bad ROM."""
    rows = []
    for spec in specs:
        found = _first_existing(spec.rom_file, search_dirs())
        actual = _file_sha1(found) if found else None
        rows.append(RomStatus(spec.id, spec.rom_file, spec.rom_sha1.lower(), found,
                              actual == spec.rom_sha1.lower(), actual))
    return rows


def import_roms(source: PathLike, specs: Iterable[RomSpec],
                dest: Optional[PathLike] = None) -> list[ImportedRom]:
    """Installs every ROM in `source` whose SHA-1 some spec expects, under that spec's file name.

    Files are matched by hash, never by name; the rest are ignored, so a file with the wrong bytes
    is never installed. Each file is written atomically (temporary file, then rename).

    Args:
        source: a folder (searched recursively), a zip or wheel, or a single ROM file.
        specs: the games whose ROMs to look for.
        dest: target folder (created if needed); default `user_rom_dir()`.

    Returns:
        One `ImportedRom` per ROM file found, in file-name order; specs absent from it had no match.

    Raises:
        FileNotFoundError: `source` does not exist.
        ValueError: two specs give one file name two different hashes.
    """
    source = Path(source).expanduser()
    if not source.exists():
        raise FileNotFoundError(f"nothing to import at {str(source)!r}")
    wanted = _manifest(specs)
    found: dict[str, tuple[str, bytes]] = {}  # sha1 -> (where, bytes); the first copy wins
    for where, data in _candidates(source):
        digest = sha1_hex(data)
        if digest in wanted and digest not in found:
            found[digest] = (where, data)
    dest = Path(dest).expanduser() if dest is not None else user_rom_dir()
    results = []
    for digest, (where, data) in found.items():
        for rom_file, game_ids in sorted(wanted[digest].items()):
            action = _write_if_changed(dest / rom_file, data, digest)
            results.append(ImportedRom(tuple(game_ids), rom_file, digest, where, dest / rom_file, action))
    return sorted(results, key=lambda r: r.rom_file)


def install_from_pypi(specs: Iterable[RomSpec], dest: Optional[PathLike] = None,
                      version: str = "0.1.1", *, timeout: float = 300.0) -> list[ImportedRom]:
    """Downloads the published `octax==version` wheel with pip and imports its ROMs (`import_roms`).

    Runs `sys.executable -m pip download --no-deps --only-binary=:all: octax==VERSION` into a
    temporary folder, so the wheel is never installed and no code from it runs.

    Raises:
        RomInstallError: pip is missing, fails or takes longer than `timeout` seconds.
    """
    with tempfile.TemporaryDirectory(prefix="octax-wheel-") as tmp:
        cmd = [sys.executable, "-m", "pip", "download", "--no-deps", "--only-binary=:all:",
               "--disable-pip-version-check", "--no-input", f"octax=={version}", "-d", tmp]
        _run_pip(cmd, timeout)
        wheels = sorted(Path(tmp).glob("octax-*.whl"))
        if not wheels:
            raise RomInstallError(f"pip reported success but left no octax wheel in {tmp}")
        return import_roms(wheels[0], specs, dest)


def _run_pip(cmd: list[str], timeout: float) -> None:
    fallback = "download the octax wheel yourself and run `octax-gym roms import WHEEL`"
    try:
        proc = subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise RomInstallError(f"pip download took over {timeout:g} s (no network?): {' '.join(cmd)}; "
                              f"or {fallback}") from None
    if proc.returncode != 0:
        tail = "\n".join((proc.stderr or proc.stdout).strip().splitlines()[-15:])
        raise RomInstallError(f"pip download failed (exit {proc.returncode}): {' '.join(cmd)}\n{tail}\n"
                              f"Check the network and pip, or {fallback}")


def _locate_verified(spec: RomSpec, path: Optional[PathLike]) -> tuple[Path, bytes]:
    if path is not None:
        found = Path(path).expanduser()
        if found.is_dir():
            found = found / spec.rom_file
        if not found.is_file():
            raise RomNotFoundError(f"game {spec.id!r}: no ROM file at {str(found)!r} "
                                   f"(expected {spec.rom_file!r}, SHA-1 {spec.rom_sha1})")
    else:
        dirs = search_dirs()
        found = _first_existing(spec.rom_file, dirs)
        if found is None:
            raise RomNotFoundError(_missing_message(spec, dirs))
    data = read_rom_file(found)  # RomTooLargeError after 65025 bytes, never the whole file
    actual = sha1_hex(data)
    if actual != spec.rom_sha1.lower():
        raise RomHashError(
            f"game {spec.id!r}: refusing ROM {str(found)!r}: SHA-1 is {actual}, expected {spec.rom_sha1}. "
            f"Remove or replace the file; to reinstall the right one, {FIX_HINT}")
    return found, data


def _file_sha1(path: Path) -> str:
    """A file's SHA-1, read in 1 MiB pieces: `rom_status` lists what is there, a 1 GiB file too,
    without holding it in memory."""
    digest = hashlib.sha1(usedforsecurity=False)
    with open(path, "rb") as file:
        for piece in iter(lambda: file.read(1 << 20), b""):
            digest.update(piece)
    return digest.hexdigest()


def _first_existing(rom_file: str, dirs: Sequence[Path]) -> Optional[Path]:
    return next((d / rom_file for d in dirs if (d / rom_file).is_file()), None)


def _missing_message(spec: RomSpec, dirs: Sequence[Path]) -> str:
    listed = "\n".join(f"  {d}" + ("" if d.is_dir() else "  (does not exist)") for d in dirs)
    return (f"no ROM for game {spec.id!r}: expected file {spec.rom_file!r} with SHA-1 {spec.rom_sha1}.\n"
            f"Searched, in order:\n{listed}\nTo fix: {FIX_HINT}.")


def _manifest(specs: Iterable[RomSpec]) -> dict[str, dict[str, list[str]]]:
    """sha1 -> {rom_file -> [game ids]}; one file name may not carry two hashes."""
    wanted: dict[str, dict[str, list[str]]] = {}
    hash_of: dict[str, str] = {}
    for spec in specs:
        digest = spec.rom_sha1.lower()
        if hash_of.setdefault(spec.rom_file, digest) != digest:
            raise ValueError(f"ROM file {spec.rom_file!r} is given two hashes: "
                             f"{hash_of[spec.rom_file]} and {digest} (game {spec.id!r})")
        wanted.setdefault(digest, {}).setdefault(spec.rom_file, []).append(spec.id)
    return wanted


def _candidates(source: Path) -> Iterator[tuple[str, bytes]]:
    """(where, bytes) for every small file in a folder, zip/wheel, or the single file given."""
    if source.is_dir():
        for root, dirnames, filenames in os.walk(source):
            dirnames.sort()
            for name in sorted(filenames):
                data = _read_small(Path(root) / name)
                if data is not None:
                    yield str(Path(root) / name), data
    elif zipfile.is_zipfile(source):
        with zipfile.ZipFile(source) as archive:
            for info in archive.infolist():
                if not info.is_dir() and info.file_size <= MAX_CANDIDATE_BYTES:
                    with archive.open(info) as member:
                        yield f"{source}:{info.filename}", member.read(MAX_CANDIDATE_BYTES + 1)
    else:
        data = _read_small(source)
        if data is not None:
            yield str(source), data


def _read_small(path: Path) -> Optional[bytes]:
    try:
        if not path.is_file() or path.stat().st_size > MAX_CANDIDATE_BYTES:
            return None
        return path.read_bytes()
    except OSError:  # unreadable files are not ROM candidates
        return None


def _write_if_changed(target: Path, data: bytes, digest: str) -> str:
    """Writes `data` to `target` atomically unless it already holds them; returns the action."""
    if target.is_file():
        if sha1_hex(target.read_bytes()) == digest:
            return "unchanged"
        action = "replaced"
    else:
        action = "installed"
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)  # mkstemp makes 0600; a ROM is not a secret
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return action
