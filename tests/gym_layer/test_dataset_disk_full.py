"""A full disk while a dataset is written (octax_gym/datasets/diskwrite.py): one named error, no
crash, no temporary file left, and the episodes written before kept and loadable.

Real processes write under a file-size limit (RLIMIT_FSIZE with SIGXFSZ ignored:
tests/dataset_disk_full_worker.py), so a write inside libhdf5 fails with EFBIG as a full disk
fails it with ENOSPC; at 68402af such a process printed h5py's `__dealloc__` tracebacks and could
die of SIGSEGV. ENOSPC itself is raised in-process by a failing `os.pwrite`.
"""

from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

minari = pytest.importorskip("minari")
h5py = pytest.importorskip("h5py")

from gymnasium import spaces  # noqa: E402

from octax_gym.datasets import recovery_spec, storage  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests"))
import dataset_kill_worker as synthetic  # noqa: E402

TIMEOUT_S = 120
LIMIT = 64 * 1024  # over metadata.json (~50 KB) and a part of three synthetic episodes (~34 KB)
PER_FLUSH = synthetic.EPISODES_PER_FLUSH


def run_worker(root: Path, mode: str, *arguments: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "MINARI_DATASETS_PATH": str(root),
           "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run([sys.executable, str(REPO / "tests" / "dataset_disk_full_worker.py"), mode, str(LIMIT),
                           *arguments], env=env, capture_output=True, text=True, timeout=TIMEOUT_S)


def assert_clean_failure(done: subprocess.CompletedProcess, root: Path) -> None:
    """No crash, no traceback or h5py `__dealloc__` noise, no temporary file anywhere."""
    assert done.returncode not in (-11, 139), done.stderr[-3000:]  # SIGSEGV
    assert "Exception ignored" not in done.stderr and "Traceback" not in done.stderr, done.stderr[-3000:]
    assert [p.name for p in root.rglob("*.tmp")] == []


def write_error(root: Path, mode: str) -> str:
    """Runs the worker's synthetic dataset `mode` past the size limit: a clean failure, with
    `DatasetWriteError` (EFBIG) raised; returns its message."""
    done = run_worker(root, mode)
    assert_clean_failure(done, root)
    assert done.returncode == 3, (done.stdout, done.stderr[-3000:])
    raised, message = done.stdout.strip().splitlines()[-2:]
    assert raised == f"raised DatasetWriteError {errno.EFBIG}"
    return message


def load(root: Path, monkeypatch, dataset_id: str = synthetic.DATASET_ID):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(root))
    return minari.load_dataset(dataset_id)


def assert_synthetic_episodes(dataset, episodes: int) -> None:
    assert dataset.total_episodes == episodes and dataset.total_steps == sum(synthetic.E_STEPS[:episodes])
    for e, stored in enumerate(dataset.iterate_episodes()):
        arrays = synthetic.episode(e).arrays(cut=False)
        for name in ("observations", "actions", "rewards", "terminations", "truncations"):
            assert np.array_equal(getattr(stored, name), arrays[name]), (e, name)


def test_a_part_past_the_limit_is_a_named_error_and_the_parts_before_it_stay(tmp_path, monkeypatch):
    message = write_error(tmp_path, "part")
    assert message.startswith("file too large writing ") and "part-00001.hdf5" in message, message
    assert f"the {PER_FLUSH} episodes" in message and "are kept" in message, message
    assert_synthetic_episodes(load(tmp_path, monkeypatch), PER_FLUSH)
    # with room again, `finish` makes the kept episodes one file
    assert storage.finish_dataset(tmp_path / synthetic.DATASET_ID)
    assert_synthetic_episodes(load(tmp_path, monkeypatch), PER_FLUSH)


def test_a_one_file_copy_past_the_limit_keeps_every_episode_in_its_parts(tmp_path, monkeypatch):
    message = write_error(tmp_path, "finish")
    assert "main_data.hdf5" in message and "dataset finish" in message, message
    all_episodes = synthetic.FLUSHES * PER_FLUSH
    data = tmp_path / synthetic.DATASET_ID / "data"
    assert sorted(p.name for p in (data / storage.PARTS).iterdir()) == [f"part-0000{i}.hdf5" for i in range(3)]
    assert_synthetic_episodes(load(tmp_path, monkeypatch), all_episodes)
    assert storage.finish_dataset(data.parent) and not (data / storage.PARTS).exists()
    assert_synthetic_episodes(load(tmp_path, monkeypatch), all_episodes)


def test_collect_past_the_limit_prints_one_error_line_and_keeps_what_it_wrote(tmp_path, monkeypatch):
    done = run_worker(tmp_path, "collect", "Brix", "--dataset-id", "octax/Brix-full-v0", "--steps", "1200",
                      "--envs", "3", "--max-episode-steps", "40", "--no-progress")
    assert_clean_failure(done, tmp_path)
    assert done.returncode == 1, (done.stdout, done.stderr[-3000:])
    assert done.stderr.count("octax-gym: error:") == 1, done.stderr[-3000:]
    line = done.stderr.strip().splitlines()[-1]
    assert line.startswith("octax-gym: error: file too large writing "), line
    assert "are kept at" in line and "octax-gym dataset finish" in line, line
    dataset = load(tmp_path, monkeypatch, "octax/Brix-full-v0")
    assert f"the {dataset.total_episodes} episodes ({dataset.total_steps} steps)" in line, line
    assert 0 < dataset.total_steps <= 1200
    assert sum(len(episode) for episode in dataset.iterate_episodes()) == dataset.total_steps


def test_no_space_left_on_device_in_process(tmp_path, monkeypatch):
    """ENOSPC from the OS at the second flush: the writer raises an OSError saying so, naming the
    part, and the process's libhdf5 is left with no file open (later files write normally)."""
    from octax_gym.datasets import diskwrite

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    writer = storage.DatasetWriter(synthetic.DATASET_ID, recovery_spec("octax/Brix-v0", {}),
                                   spaces.Box(0, 1, synthetic.SHAPE, np.uint8), spaces.Discrete(5), flush_steps=10**9,
                                   metadata={})
    for e in range(PER_FLUSH):
        writer.add(synthetic.episode(e), cut=False)
    writer.flush()
    real_pwrite, calls = os.pwrite, [0]

    def full(fd, data, offset):
        calls[0] += 1
        if calls[0] > 2:  # a few writes reach the disk, then it is full
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_pwrite(fd, data, offset)

    monkeypatch.setattr(diskwrite.os, "pwrite", full)
    for e in range(PER_FLUSH, 2 * PER_FLUSH):
        writer.add(synthetic.episode(e), cut=False)
    with pytest.raises(OSError) as raised:
        writer.flush()
    assert isinstance(raised.value, diskwrite.DatasetWriteError) and raised.value.errno == errno.ENOSPC
    assert str(raised.value).startswith("no space left on device writing ") and "part-00001.hdf5" in str(raised.value)
    assert [p.name for p in tmp_path.rglob("*.tmp")] == []
    assert h5py.h5f.get_obj_count(h5py.h5f.OBJ_ALL, h5py.h5f.OBJ_FILE) == 0
    assert_synthetic_episodes(minari.load_dataset(synthetic.DATASET_ID), PER_FLUSH)


def test_what_is_written_after_a_failed_write_reads_back_from_memory(tmp_path, monkeypatch):
    """libhdf5 may read back what it wrote: after the failure, the held bytes over the disk's, and
    zeros past the end, as libhdf5's own driver reads."""
    from octax_gym.datasets import diskwrite

    real_pwrite = os.pwrite

    def limited(fd, data, offset):  # the disk takes bytes up to offset 8, then is full
        if offset + len(data) > 8:
            if offset >= 8:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            data = bytes(data)[:8 - offset]
        return real_pwrite(fd, data, offset)

    with open(tmp_path / "f", "w+b", buffering=0) as raw:
        sink = diskwrite._Sink(raw)
        monkeypatch.setattr(diskwrite.os, "pwrite", limited)
        sink.write(b"abcdef")
        assert sink.error is None
        sink.write(b"GHIJ")  # 2 bytes reach the disk, then ENOSPC
        assert sink.error is not None and sink.error.errno == errno.ENOSPC
        sink.seek(14)
        sink.write(b"xy")
        sink.seek(2)
        sink.write(b"CD")  # over bytes on the disk
        sink.seek(0)
        assert sink.read(20) == b"abCDefGHIJ\0\0\0\0xy\0\0\0\0"
        assert sink.seek(0, os.SEEK_END) == 16 and sink.truncate(12) == 12
        sink.seek(8)
        assert sink.read(8) == b"IJ\0\0\0\0\0\0"
    assert (tmp_path / "f").read_bytes() == b"abcdefGH"  # the disk holds what it took
