"""A process of tests/gym_layer/test_dataset_kill.py: writes a synthetic dataset and SIGKILLs
itself at one chosen point inside the writer (a kill point), the way a cluster's preemption or an
out-of-memory kill would end a collection: no exception, no cleanup, no `finally`.

    python tests/dataset_kill_worker.py KILL_POINT      (MINARI_DATASETS_PATH set by the caller)

Episode e (0-based) has seed e, E_STEPS[e] steps and frames drawn from default_rng(e); episodes go
to the writer with flush_steps=FLUSH_STEPS, so each flush holds EPISODES_PER_FLUSH episodes. The
kill points, each in the second flush or later unless it says otherwise:
    none        no kill: close() runs
    create      inside the dataset's creation (after Minari wrote it, before it is in place)
    part        while the second part's episodes are being written
    index       while main_data.hdf5's new links are being added
    metadata    while the second flush's metadata.json is being written (the data file is in place)
    finish      while close() copies the episodes into one file
    cleanup     in close(), after the one file is in place, before the parts are deleted
"""

import os
import signal
import sys

import numpy as np

DATASET_ID = "octax/Killed-v0"
SHAPE = (4, 32, 64)
EPISODES_PER_FLUSH, FLUSHES = 3, 3
E_STEPS = [7, 5, 9, 6, 8, 4, 10, 3, 5]



def episode(e):
    from octax_gym.datasets import EpisodeRecord

    rng = np.random.default_rng(e)
    record = EpisodeRecord(e, rng.integers(0, 2, SHAPE).astype(np.uint8), {"score": np.float32(0)})
    for t in range(E_STEPS[e]):
        record.add(int(rng.integers(0, 5)), rng.integers(0, 2, SHAPE).astype(np.uint8), float(t),
                   t == E_STEPS[e] - 1, False, {"score": np.float32(t + 1)})
    return record


def die():
    os.kill(os.getpid(), signal.SIGKILL)


def count_calls(owner, name, kill_at, when=lambda *a, **k: True):
    """Wraps owner.name so that its kill_at-th call (1-based) that `when` accepts kills the process."""
    original = getattr(owner, name)
    calls = [0]

    def wrapped(*args, **kwargs):
        if when(*args, **kwargs):
            calls[0] += 1
            if calls[0] == kill_at:
                die()
        return original(*args, **kwargs)
    setattr(owner, name, wrapped)


def main(point):
    import h5py
    from gymnasium import spaces

    from octax_gym.datasets import recovery_spec, storage

    if point == "create":
        count_calls(storage, "update_metadata", 1)  # its first call completes the staged dataset
    elif point == "part":
        count_calls(storage.DatasetWriter, "_write_episode", EPISODES_PER_FLUSH + 2)
    elif point == "index":
        count_calls(h5py, "ExternalLink", EPISODES_PER_FLUSH + 2)
    elif point == "metadata":
        original = storage._replacing.__exit__
        calls = [0]

        def exit_(self, *exc):  # the temporary metadata.json is written, not yet renamed
            if self.path.name == storage.METADATA:
                calls[0] += 1
                if calls[0] == 3:  # 1: creation, 2: first flush, 3: second flush
                    die()
            return original(self, *exc)
        storage._replacing.__exit__ = exit_
    elif point == "finish":
        count_calls(h5py.Group, "copy", EPISODES_PER_FLUSH + 1)
    elif point == "cleanup":
        count_calls(storage.shutil, "rmtree", 1, when=lambda path, *a, **k: str(path).endswith(storage.PARTS))
    elif point != "none":
        raise SystemExit(f"unknown kill point {point!r}")
    writer = storage.DatasetWriter(DATASET_ID, recovery_spec("octax/Brix-v0", {}), spaces.Box(0, 1, SHAPE, np.uint8),
                                   spaces.Discrete(5), flush_steps=10**9, metadata={"algorithm_name": "kill test"})  # flushed by hand
    for f in range(FLUSHES):
        for e in range(f * EPISODES_PER_FLUSH, (f + 1) * EPISODES_PER_FLUSH):
            writer.add(episode(e), cut=False)
        writer.flush()
        print("flushed", f + 1, flush=True)
    writer.close()
    print("closed", flush=True)


if __name__ == "__main__":
    main(sys.argv[1])
