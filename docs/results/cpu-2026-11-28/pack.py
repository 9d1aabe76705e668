"""Copies a finished `octax-gym train` run into this folder, its agents as float16 (half the bytes;
`jax_policy.load_agent` reads them back as float32): progress.csv, config.json, summary.json,
learning_curve.png and agents/*.msgpack (not the step snapshots, not the resume checkpoint).

    python docs/results/cpu-2026-11-28/pack.py RUN_DIR docs/results/cpu-2026-11-28/NAME
"""
import shutil
import sys
from pathlib import Path

import flax.serialization
import numpy as np

run, out = Path(sys.argv[1]), Path(sys.argv[2])
(out / "agents").mkdir(parents=True, exist_ok=True)
for name in ("progress.csv", "config.json", "summary.json", "learning_curve.png"):
    shutil.copyfile(run / name, out / name)


def half(tree):
    if isinstance(tree, dict):
        return {key: half(value) for key, value in tree.items()}
    return tree.astype(np.float16) if isinstance(tree, np.ndarray) and tree.dtype == np.float32 else tree


for path in sorted((run / "agents").glob("*-seed[0-9].msgpack")):
    saved = flax.serialization.msgpack_restore(path.read_bytes())
    (out / "agents" / path.name).write_bytes(flax.serialization.msgpack_serialize(half(saved)))
print("packed", run, "->", out)
