"""Packs a train run's files into $OUT within the device tool's limits (8 files, 16 MiB each):
progress.csv, config.json, summary.json, learning_curve.png, and each game's seed-0 agent in
float16, in two tar files."""
import io, sys, tarfile
from pathlib import Path
import numpy as np
import flax.serialization as ser
import jax

run, out = Path(sys.argv[1]), Path(sys.argv[2])
for name in ("progress.csv", "config.json", "summary.json", "learning_curve.png"):
    if (run / name).exists():
        (out / name).write_bytes((run / name).read_bytes())
agents = sorted((run / "agents").glob("*-seed0.msgpack"))
half = (len(agents) + 1) // 2
for part, chunk in enumerate((agents[:half], agents[half:])):
    with tarfile.open(out / f"agents-seed0-{part}.tar", "w") as tar:
        for path in chunk:
            tree = ser.msgpack_restore(path.read_bytes())
            tree = jax.tree.map(lambda x: np.asarray(x, np.float16) if np.asarray(x).dtype == np.float32 else x, tree)
            data = ser.msgpack_serialize(tree)
            info = tarfile.TarInfo(path.name); info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
print("packed", len(agents), "agents")
