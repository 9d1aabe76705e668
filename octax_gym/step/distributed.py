"""Many processes, one batch: JAX's own distributed runtime, started the way launchers start it.

    import octax_gym.distributed, gymnasium as gym
    octax_gym.distributed.initialize()                  # under SLURM or torchrun-style variables
    envs = gym.make_vec("octax/Pong-v0", num_envs=4096, devices="all")   # this process's lanes
    envs.global_env_ids                                  # their indices in the global batch

`initialize` calls `jax.distributed.initialize` (before anything else touches JAX) with, in order:
the arguments given; else the torchrun-style variables MASTER_ADDR, MASTER_PORT, WORLD_SIZE and
RANK; else nothing, which lets JAX detect SLURM (and other clusters) itself. On CPU it selects
Gloo for the collectives, so CPU-only processes (this machine, CI) can run a sharded batch too.

JAX checks little itself and answers most start-up mistakes by aborting the process (SIGABRT, no
Python exception, after its timeout), or not at all (ranks that disagree on the process count
joined as the smaller run). So when the coordinator's address is known, the processes first meet
on its port through a handshake of our own: process 0 holds the port, every other process sends
its (num_processes, process_id), and process 0 answers every one once all have come, then frees
the port for JAX's coordinator. A count that differs from process 0's, an id given twice, a port
held by a program that does not speak the handshake, a coordinator that cannot be reached or
processes that do not come within `timeout_s` are each a `DistributedInitError` naming the
mismatch, on every process that took part. What is left to JAX (a process that stops between the
handshake and JAX's own registration, runs started from SLURM's variables, which skip the
handshake) still aborts; the line printed before calling JAX names the likely causes. See
docs/scale.md, "Start-up failures".
"""

from __future__ import annotations

import os
import sys
from typing import Optional

import jax

from octax_gym.step import handshake

TORCHRUN_VARIABLES = ("MASTER_ADDR", "MASTER_PORT", "WORLD_SIZE", "RANK")


class DistributedInitError(RuntimeError):
    """The distributed runtime could not start: the coordinator, processes and cause named."""


def initialize(coordinator_address: Optional[str] = None, num_processes: Optional[int] = None,
               process_id: Optional[int] = None, *, timeout_s: int = 300, cpu_collectives: str = "gloo") -> None:
    """Joins this process to the run (`jax.distributed.initialize`); see the module docstring.

    Args:
        coordinator_address: "host:port" of process 0's coordinator service.
        num_processes, process_id: the run's size and this process's rank.
        timeout_s: how long to wait for every process to join (the handshake, then JAX, each this long).
        cpu_collectives: the CPU collectives implementation ("gloo"; "mpi" where JAX has it).

    Raises:
        DistributedInitError: the coordinator was not reached, its port answered something else, the
            processes disagree on the process count or give an id twice, or not every process came in time.
        ValueError: a partial set of torchrun-style variables, or a bad address, rank or size.
    """
    if coordinator_address is None and num_processes is None and process_id is None:
        coordinator_address, num_processes, process_id = _from_torchrun_variables()
    _check_arguments(coordinator_address, num_processes, process_id)
    met = coordinator_address is not None and num_processes > 1
    if met:
        try:
            handshake.meet(coordinator_address, num_processes, process_id, timeout_s)
        except handshake.HandshakeError as exc:
            raise DistributedInitError(str(exc)) from None
    jax.config.update("jax_cpu_collectives_implementation", cpu_collectives)
    where = coordinator_address or "the address JAX detected from the cluster's variables"
    if num_processes != 1:  # JAX ends the process without a Python exception when registering fails: say why first
        print(_abort_warning(process_id, num_processes, where, met), file=sys.stderr, flush=True)
    try:
        jax.distributed.initialize(coordinator_address, num_processes, process_id,
                                   initialization_timeout=timeout_s)
    except Exception as exc:  # XLA's DEADLINE_EXCEEDED and connection errors, as JaxRuntimeError/RuntimeError
        raise DistributedInitError(
            f"process {process_id} of {num_processes} could not join the run coordinated at {where} within "
            f"{timeout_s} s: is process 0 running, reachable there, and are all {num_processes} processes "
            f"started? ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})") from exc


def _abort_warning(process_id, num_processes, where: str, met: bool) -> str:
    """The line printed before JAX's registration: the causes left when this process ends without a traceback."""
    causes = ("another process stopped between the start-up handshake and JAX's registration" if met else
              "with no start-up handshake (the cluster gave the address), a process that never started, processes "
              "that disagree on the process count, an id given twice, or a coordinator port held by another program")
    return (f"octax-gym: process {process_id} of {num_processes} is joining JAX's runtime at {where}; if JAX now "
            f"ends it (SIGABRT, no Python exception), the likely cause is {causes} (docs/scale.md, 'Start-up "
            f"failures')")


def _from_torchrun_variables() -> tuple:
    """The address, size and rank the torchrun-style variables give, or three Nones when none is set."""
    present = [name for name in TORCHRUN_VARIABLES if name in os.environ]
    if not present:
        return None, None, None
    if len(present) != len(TORCHRUN_VARIABLES):
        missing = sorted(set(TORCHRUN_VARIABLES) - set(present))
        raise ValueError(f"torchrun-style launch variables set in part: {', '.join(present)} without "
                         f"{', '.join(missing)}")
    sizes = []
    for name in ("WORLD_SIZE", "RANK"):
        try:
            sizes.append(int(os.environ[name]))
        except ValueError:
            raise ValueError(f"{name} must be an integer, got {os.environ[name]!r}") from None
    return f"{os.environ['MASTER_ADDR']}:{os.environ['MASTER_PORT']}", *sizes


def _check_arguments(coordinator_address, num_processes, process_id) -> None:
    """Refuses what JAX would abort on, or take silently, before anything starts."""
    if (num_processes is None) != (process_id is None):
        raise ValueError(f"num_processes and process_id go together: got num_processes={num_processes}, "
                         f"process_id={process_id}")
    if num_processes is not None:
        if not handshake.is_int(num_processes) or num_processes < 1:
            raise ValueError(f"num_processes must be an integer >= 1, got {num_processes!r}")
        if not handshake.is_int(process_id) or not 0 <= process_id < num_processes:
            raise ValueError(f"process_id must be in 0..num_processes - 1, got process_id={process_id!r}, "
                             f"num_processes={num_processes}")
    if coordinator_address is not None:
        handshake.split_address(coordinator_address)
