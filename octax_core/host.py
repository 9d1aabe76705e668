"""The size of XLA:CPU's thread pool: how many threads run one jitted step on the host.

XLA:CPU runs a step as a sequence of small kernels ("thunks") on a pool of one thread per core,
handing ready kernels and the halves of large loops to the other threads. An emulator step is
many kernels of a few microseconds each, so on a host with few cores the handoffs can cost more
than the work they share: a small batch runs faster with a one-thread pool, while a large one
gains from the second thread (its kernels are large enough for the split to pay), and so does
other work with larger kernels, such as the octax package's env. So the pool keeps JAX's default
unless asked (the measurements: docs/machine-log.md, "The thread pool").

JAX offers no setting for it: XLA sizes the pool from the cores the process may run on when the
CPU backend starts. `limit_cpu_threads` starts the backend while the process may run on
`threads` of its cores, then gives every thread of the process its cores back; only the pool's
size stays. Setting the environment variable ``OCTAX_CPU_THREADS`` does the same when
`octax_core` is imported.
"""

from __future__ import annotations

import os
import warnings

from octax_core.validate import check_int

ENV_VAR = "OCTAX_CPU_THREADS"


def limit_cpu_threads(threads: int) -> None:
    """Starts JAX's backends with `threads` threads in XLA:CPU's pool (one per core by default).

    Call it before anything runs on JAX (or set ``OCTAX_CPU_THREADS`` before importing
    `octax_core`): the pool is sized once, when the CPU backend starts.

    Raises:
        ValueError: `threads` is not an int from 1 to the cores this process may use.
        RuntimeError: JAX's backends have already started, or this OS cannot restrict a
            process to some of its cores (Linux can).
    """
    from jax._src import xla_bridge

    if not hasattr(os, "sched_getaffinity"):
        raise RuntimeError("limit_cpu_threads needs os.sched_setaffinity (Linux); the pool keeps JAX's default")
    cores = sorted(os.sched_getaffinity(0))
    threads = check_int("threads", threads, 1, len(cores))
    if xla_bridge.backends_are_initialized():
        raise RuntimeError(f"JAX's backends have already started, so their CPU thread pool is sized; call "
                           f"limit_cpu_threads({threads}) before anything runs on JAX, or set {ENV_VAR}={threads} "
                           f"before importing octax_core")
    import jax

    os.sched_setaffinity(0, cores[:threads])
    try:
        jax.devices()  # the backends start here, and XLA:CPU sizes its pool from the cores allowed
    finally:
        for task in os.listdir("/proc/self/task") if os.path.isdir("/proc/self/task") else ["0"]:
            try:  # every thread started meanwhile (the pool's among them) gets all the cores back
                os.sched_setaffinity(int(task), cores)
            except OSError:  # a thread that ended in the meantime
                pass


def apply_environment() -> None:
    """`limit_cpu_threads(OCTAX_CPU_THREADS)` when the variable is set (at `import octax_core`).
    A bad value raises; a backend already started makes it a warning, since the import itself
    cannot be undone."""
    value = os.environ.get(ENV_VAR, "").strip()
    if not value:
        return
    try:
        threads = int(value)
    except ValueError:
        raise ValueError(f"{ENV_VAR} must be an int >= 1 (XLA:CPU threads), got {value!r}") from None
    try:
        limit_cpu_threads(threads)
    except RuntimeError as exc:
        warnings.warn(f"{ENV_VAR}={value} ignored: {exc}", RuntimeWarning, stacklevel=3)
