"""The timing harness every benchmark script here shares: compile, time interleaved, print one line.

A benchmark prepares each side of a comparison (`Prepared`: a no-argument run plus its compile
time and state size), times the sides alternately (`time_interleaved`, so a burst of load from
elsewhere hits every side rather than one), and prints free-form lines, then exactly one summary
line per case, `BENCH <name> key=value ...` (`bench_line`), which `parse_bench_lines` reads back.

XLA fixes the number of CPU devices at JAX's first computation, not at `import jax`, so
`set_host_devices` must run before anything computes; it says so when it is too late. This
module imports JAX only inside functions.
"""

from __future__ import annotations

import dataclasses
import os
import platform
import sys
import time
from pathlib import Path
from typing import Callable, Optional

REPO_ROOT = Path(__file__).resolve().parent.parent
DEFAULT_ROM_DIR = "../shared/roms/octax"


class BenchError(ValueError):
    """An option this run cannot honour (device count, held key); reported with exit status 1."""


@dataclasses.dataclass
class Prepared:
    """One side of a comparison, compiled and ready to time."""

    run: Callable[[], object]  # one whole rollout; the caller blocks on the result
    compile_s: float           # lower + compile of the whole rollout (gym: first reset + step)
    state_bytes: int           # bytes of one env's state
    instructions_per_step: int
    devices: int = 1           # devices the batch was actually split over
    setup: Callable[[], None] = lambda: None  # run, untimed, before each timed run
    best_s: float = float("inf")


def set_host_devices(n: int) -> None:
    """Asks XLA for n CPU devices; works until JAX's first computation in this process.

    Raises:
        BenchError: JAX has already computed something with another device count.
    """
    if n == 1:
        return
    import jax

    try:
        jax.config.update("jax_num_cpu_devices", n)
    except AttributeError:  # a JAX without the option: its CPU backend reads the flag when it starts
        flag = f"--xla_force_host_platform_device_count={n}"
        os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + flag).strip()
    except RuntimeError as exc:
        raise BenchError(f"--devices {n}: JAX has already run a computation in this process, which fixed "
                         f"its device count; start a new process") from exc


def find_rom(game: str, explicit: Optional[Path]) -> Path:
    """The verified ROM of `game`: `explicit`, else the ROM store, else DEFAULT_ROM_DIR from the repository root."""
    from octax_core.env import romstore
    from octax_core.env.games import get_spec

    spec = get_spec(game)
    if explicit is not None:
        return romstore.find_rom(spec, explicit)
    try:
        return romstore.find_rom(spec)
    except romstore.RomNotFoundError:
        beside_repo = REPO_ROOT / os.environ.get("OCTAX_ROM_DIR", DEFAULT_ROM_DIR)
        if not (beside_repo / spec.rom_file).is_file():
            raise
        return romstore.find_rom(spec, beside_repo)


def state_bytes(batched_state) -> int:
    """Bytes of one env's state: the sum of nbytes over the leaves, batch dimension removed."""
    import jax
    import numpy as np

    total = 0
    for leaf in jax.tree.leaves(batched_state):
        if jax.dtypes.issubdtype(leaf.dtype, jax.dtypes.prng_key):
            leaf = jax.random.key_data(leaf)
        total += int(np.prod(leaf.shape[1:], dtype=np.int64)) * leaf.dtype.itemsize
    return total


def _shard_map(f, **kwargs):
    import jax

    if hasattr(jax, "shard_map"):
        return jax.shard_map(f, check_vma=False, **kwargs)
    from jax.experimental.shard_map import shard_map  # jax < 0.7

    return shard_map(f, check_rep=False, **kwargs)


def compile_rollout(rollout: Callable, inputs, actions, devices: int = 1, compiler_options=None):
    """jit (and, for several devices, shard_map over the batch axis) then AOT-compile.

    `compiler_options`: ours pass the platform's (`env.compiler_options`, as octax-gym's own
    steps compile); the octax package's rollout compiles as that package does, with none.

    Returns a no-argument function running the compiled rollout on its inputs (placed where it
    wants them), the compile time and the number of devices used (1 when N does not split evenly).
    """
    import jax
    from jax.sharding import NamedSharding, PartitionSpec as P

    n = actions.shape[0]
    if devices > 1 and n % devices == 0:
        mesh = jax.make_mesh((devices,), ("env",))
        # Each device runs the plain per-env rollout on its slice; nothing crosses devices. The
        # varying-manual-axes check is off because it also rejects loop carries that start as
        # constants inside the code under test (octax's or ours), which is harmless here.
        fn = jax.jit(_shard_map(rollout, mesh=mesh, in_specs=(P("env"), P("env")), out_specs=P("env")),
                     compiler_options=compiler_options)
        inputs, actions = jax.device_put((inputs, actions), NamedSharding(mesh, P("env")))
    else:
        devices, fn = 1, jax.jit(rollout, compiler_options=compiler_options)
    inputs, actions = jax.block_until_ready((inputs, actions))
    t0 = time.perf_counter()
    compiled = fn.lower(inputs, actions).compile()
    return (lambda: compiled(inputs, actions)), time.perf_counter() - t0, devices


class Progress:
    """A tqdm bar on stderr over compiles, warm-ups and timed runs; lines printed through it go
    to stdout without tearing the bar. Off: plain prints."""

    def __init__(self, total: int, enabled: bool):
        self._bar = None
        if enabled:
            from tqdm import tqdm

            self._bar = tqdm(total=total, file=sys.stderr, unit="run", dynamic_ncols=True, leave=False)

    def stage(self, text: str) -> None:
        if self._bar is not None:
            self._bar.set_description_str(text)

    def advance(self) -> None:
        if self._bar is not None:
            self._bar.update(1)

    def print(self, line: str) -> None:
        if self._bar is None:
            print(line, flush=True)
        else:
            self._bar.write(line, file=sys.stdout)
            sys.stdout.flush()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


def time_interleaved(sides: dict[str, Prepared], repeats: int, progress: Progress, label: str) -> None:
    """Best wall time of each side over `repeats` runs, alternating sides so all see the same load."""
    import jax

    for name, side in sides.items():
        progress.stage(f"{label} {name}: warm-up")
        side.setup()
        jax.block_until_ready(side.run())  # the first run allocates buffers
        progress.advance()
    for i in range(repeats):
        for name, side in sides.items():
            progress.stage(f"{label} {name}: run {i + 1}/{repeats}")
            side.setup()
            t0 = time.perf_counter()
            jax.block_until_ready(side.run())
            side.best_s = min(side.best_s, time.perf_counter() - t0)
            progress.advance()


def machine_line(rom: Path) -> str:
    """The first line of every benchmark's output: versions, backend, devices, cores, ROM."""
    import jax

    return (f"# jax {jax.__version__} backend={jax.default_backend()} devices={jax.device_count()} "
            f"python {platform.python_version()} cpus={os.cpu_count()} "
            f"xla_cpu_threads={os.environ.get('OCTAX_CPU_THREADS') or 'default'} rom={rom.name}")


def load_average() -> float:
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")


def bench_line(name: str, fields: dict) -> str:
    """`BENCH <name> k=v ...`; None values print as `na`."""
    return f"BENCH {name} " + " ".join(f"{k}={'na' if v is None else v}" for k, v in fields.items())


def parse_bench_lines(out: str, name: str) -> list[dict[str, str]]:
    """Each `BENCH <name> k=v ...` line of `out` as an ordered dict of strings."""
    prefix = f"BENCH {name} "
    return [dict(field.split("=", 1) for field in line[len(prefix):].split())
            for line in out.splitlines() if line.startswith(prefix)]
