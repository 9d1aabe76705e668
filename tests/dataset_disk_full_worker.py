"""A process of tests/gym_layer/test_dataset_disk_full.py: writes a dataset under a file-size limit
(RLIMIT_FSIZE, SIGXFSZ ignored), so that a write fails part way with EFBIG inside libhdf5, as a full
disk fails it with ENOSPC, without filling the machine's disk.

    python tests/dataset_disk_full_worker.py MODE LIMIT_BYTES     (MINARI_DATASETS_PATH set by the caller)

Modes:
    part     the synthetic episodes of tests/dataset_kill_worker.py, flushed in groups of three, then
             one episode of BIG_STEPS steps whose part is larger than the limit
    finish   the nine synthetic episodes in three parts, each under the limit; close()'s one file is
             larger than it
    collect  `octax-gym dataset collect Brix ...` (the arguments after LIMIT_BYTES), the collector's
             groups made COLLECT_FLUSH_STEPS steps long so that a short collection writes parts

The writer modes print `raised <type> <errno>` and the message, and exit 3, when the writer raises
an OSError; `collect` exits with the command line's status.
"""

import functools
import os
import resource
import signal
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import dataset_kill_worker as synthetic  # noqa: E402

BIG_STEPS = 100  # ~100 KB of incompressible frames: over the tests' 64 KB limit
COLLECT_FLUSH_STEPS = 150


def big_episode(seed: int):
    from octax_gym.datasets import EpisodeRecord

    rng = np.random.default_rng(seed)
    record = EpisodeRecord(seed, rng.integers(0, 2, synthetic.SHAPE).astype(np.uint8), {"score": np.float32(0)})
    for t in range(BIG_STEPS):
        record.add(int(rng.integers(0, 5)), rng.integers(0, 2, synthetic.SHAPE).astype(np.uint8), float(t),
                   t == BIG_STEPS - 1, False, {"score": np.float32(t + 1)})
    return record


def write(mode: str) -> int:
    from gymnasium import spaces

    from octax_gym.datasets import recovery_spec, storage

    writer = storage.DatasetWriter(synthetic.DATASET_ID, recovery_spec("octax/Brix-v0", {}),
                                   spaces.Box(0, 1, synthetic.SHAPE, np.uint8), spaces.Discrete(5), flush_steps=10**9,
                                   metadata={"algorithm_name": "disk full test"})
    try:
        for f in range(synthetic.FLUSHES if mode == "finish" else 1):
            for e in range(f * synthetic.EPISODES_PER_FLUSH, (f + 1) * synthetic.EPISODES_PER_FLUSH):
                writer.add(synthetic.episode(e), cut=False)
            writer.flush()
            print("flushed", f + 1, flush=True)
        if mode == "part":
            writer.add(big_episode(synthetic.EPISODES_PER_FLUSH), cut=False)
            writer.flush()
        writer.close()
    except OSError as exc:
        print("raised", type(exc).__name__, exc.errno, flush=True)
        print(exc, flush=True)
        return 3
    print("closed", flush=True)
    return 0


def collect(arguments: list[str]) -> int:
    from octax_gym import cli
    from octax_gym.datasets import collect as collect_module

    collect_module.collect_dataset = functools.partial(collect_module.collect_dataset,
                                                       flush_steps=COLLECT_FLUSH_STEPS)
    return cli.main(["dataset", "collect", *arguments])


def main(mode: str, limit: int, arguments: list[str]) -> int:
    if mode not in ("part", "finish", "collect"):
        raise SystemExit(f"unknown mode {mode!r}: part, finish or collect")
    # No persistent JAX compilation cache here: its entries written under the limit would be cut
    # short, in a folder other runs read.
    os.environ.pop("JAX_COMPILATION_CACHE_DIR", None)
    os.environ["JAX_ENABLE_COMPILATION_CACHE"] = "false"
    from octax_gym.datasets.storage import import_minari

    import_minari()  # the modules loaded before the limit (a bytecode cache write would meet it)
    if mode == "collect":
        import octax_gym.cli  # noqa: F401
        import octax_gym.datasets.collect  # noqa: F401
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG instead
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.getrlimit(resource.RLIMIT_FSIZE)[1]))
    return collect(arguments) if mode == "collect" else write(mode)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], int(sys.argv[2]), sys.argv[3:]))
