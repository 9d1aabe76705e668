"""HDF5 files written so that a full disk is one Python exception naming the file, never a crash.

Through h5py's own file driver, libhdf5 meets a failed write (ENOSPC, EFBIG past a file-size
limit, EDQUOT) inside its caches: the file stays open with metadata it can neither write nor
drop, every later close of an object in it prints a RuntimeError from h5py's `__dealloc__`
("Exception ignored"), and libhdf5 flushing that file again as the interpreter exits crashes it.
Measured at 68402af: `octax-gym dataset collect` on a 2 MB tmpfs printed 6,490 lines of those
and died of SIGSEGV (exit 139), a `.part-*.tmp` file left behind.

Here libhdf5 writes through a Python file object instead (h5py's `fileobj` driver) that never
fails towards it: the first OSError is kept, the bytes from then on are held in memory (so that
libhdf5 reads back what it wrote, as from a file), the writer stops at its next `check()`, the
file closes cleanly, and the kept error comes out as a `DatasetWriteError` naming the file. The
bytes held are those written between the failure and the next check: an episode at most, and
the closing metadata.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path
from typing import Optional

# A write failing with one of these means the disk (or the process's share of it) is full; the
# folder's other files are whole and the dataset is kept as it is.
OUT_OF_SPACE = frozenset({errno.ENOSPC, errno.EFBIG, errno.EDQUOT})


class DatasetWriteError(OSError):
    """A dataset file could not be written: the failed write's errno, the file it was for, and
    what happened to the dataset (`outcome`: what is kept, what to do)."""

    def __init__(self, code: int, path, outcome: str = ""):
        super().__init__(code, os.strerror(code), str(path))
        self.outcome = outcome

    def __str__(self) -> str:
        reason = self.strerror[:1].lower() + self.strerror[1:]
        return f"{reason} writing {self.filename}" + (f": {self.outcome}" if self.outcome else "")

    def with_outcome(self, outcome: str) -> "DatasetWriteError":
        """The same failure, saying what happened to the dataset."""
        return DatasetWriteError(self.errno, self.filename, outcome)


def is_out_of_space(exc: BaseException) -> bool:
    return isinstance(exc, OSError) and exc.errno in OUT_OF_SPACE


class HDF5Writing:
    """`with HDF5Writing(path, "w") as out:` write `out.file` (an h5py.File: "w" creates the
    file, "r+" adds to it), calling `out.check()` between pieces of work; a failed write raises
    `DatasetWriteError` at the next check or when the block ends, after libhdf5 closed the file."""

    def __init__(self, path, mode: str):
        if mode not in ("w", "r+"):
            raise ValueError(f"mode must be 'w' or 'r+', got {mode!r}")
        self.path, self._mode = Path(path), mode
        self._sink: Optional[_Sink] = None
        self.file = None

    def __enter__(self) -> "HDF5Writing":
        import h5py

        from octax_gym.datasets.storage import LIBVER

        try:
            raw = open(self.path, "w+b" if self._mode == "w" else "r+b", buffering=0)
        except OSError as exc:
            if is_out_of_space(exc):
                raise DatasetWriteError(exc.errno, self.path) from exc
            raise
        self._sink = _Sink(raw)
        try:
            self.file = h5py.File(self._sink, self._mode, libver=LIBVER, track_order=True)
        except BaseException:
            raw.close()
            self.check()
            raise
        return self

    def check(self) -> None:
        """Raises the failed write, if there was one, as a `DatasetWriteError` for this file."""
        if self._sink is not None and self._sink.error is not None:
            error = self._sink.error
            raise DatasetWriteError(error.errno or errno.EIO, self.path) from error

    def __exit__(self, kind, value, traceback):
        try:
            self.file.close()  # libhdf5's last writes: the metadata, the superblock
        except Exception:
            if self._sink.error is None:
                raise
        finally:
            self._sink.close()
        if kind is None or (issubclass(kind, Exception) and not isinstance(value, DatasetWriteError)):
            self.check()  # a failed write is the cause, whatever libhdf5 or the caller raised since
        return False


class _Sink:
    """A read-write binary file for h5py's `fileobj` driver that never raises on a write: the
    first failed write's OSError is kept in `error`, and that write and every later one are held
    in memory instead, where reads find them."""

    def __init__(self, raw):
        self._raw = raw
        self._pos = 0
        self._held: list[tuple[int, bytes]] = []  # (offset, bytes) written after the failure, in order
        self._size = os.fstat(raw.fileno()).st_size
        self.error: Optional[OSError] = None

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        self._pos = offset + (self._pos if whence == os.SEEK_CUR else self._size if whence == os.SEEK_END else 0)
        return self._pos

    def tell(self) -> int:
        return self._pos

    def write(self, data) -> int:
        data = bytes(data)
        if self.error is None:
            try:
                self._write_all(self._pos, data)
            except OSError as exc:
                self.error = exc
        if self.error is not None:
            self._held.append((self._pos, data))
        self._pos += len(data)
        self._size = max(self._size, self._pos)
        return len(data)

    def read(self, size: int = -1) -> bytes:
        """`size` bytes from the position: from the disk, zeros past its end (as libhdf5's own
        driver reads), and over them the bytes held since a failed write."""
        size = max(self._size - self._pos, 0) if size < 0 else size
        start, end = self._pos, self._pos + size
        out = bytearray(os.pread(self._raw.fileno(), size, start) if size else b"")
        out.extend(bytes(size - len(out)))
        for offset, data in self._held:
            low, high = max(offset, start), min(offset + len(data), end)
            if low < high:
                out[low - start:high - start] = data[low - offset:high - offset]
        self._pos = end
        return bytes(out)

    def truncate(self, size: Optional[int] = None) -> int:
        size = self._pos if size is None else size
        if self.error is None:
            try:
                self._raw.truncate(size)
            except OSError as exc:
                self.error = exc
        self._held = [(offset, data[:size - offset]) for offset, data in self._held if offset < size]
        self._size = size
        return size

    def flush(self) -> None:
        pass  # unbuffered: every write has reached the OS or failed

    def close(self) -> None:
        self._raw.close()

    def _write_all(self, offset: int, data: bytes) -> None:
        view = memoryview(data)
        while view:
            written = os.pwrite(self._raw.fileno(), view, offset)
            view, offset = view[written:], offset + written
