"""Many processes, one batch: JAX's own distributed runtime, started the way launchers start it.

    import octax_gym.distributed, gymnasium as gym
    octax_gym.distributed.initialize()                  # under SLURM or torchrun-style variables
    envs = gym.make_vec("octax/Pong-v0", num_envs=4096, devices="all")   # this process's lanes
    envs.global_env_ids                                  # their indices in the global batch

`initialize` calls `jax.distributed.initialize` (before anything else touches JAX) with, in order:
the arguments given; else the torchrun-style variables MASTER_ADDR, MASTER_PORT, WORLD_SIZE and
RANK; else nothing, which lets JAX detect SLURM (and other clusters) itself. On CPU it selects
Gloo for the collectives, so CPU-only processes (this machine, CI) can run a sharded batch too.
A coordinator that cannot be reached within `timeout_s` is a `DistributedInitError` naming it,
never a hang: the other processes wait for process 0's port to open before they join (JAX itself
aborts the whole process, with no Python exception, when registering with a coordinator times
out). Process 0 waits `timeout_s` for the others to join, then JAX ends it with its
DEADLINE_EXCEEDED error. See docs/scale.md.
"""

from __future__ import annotations

import os
import socket
import time
from typing import Optional

import jax

TORCHRUN_VARIABLES = ("MASTER_ADDR", "MASTER_PORT", "WORLD_SIZE", "RANK")


class DistributedInitError(RuntimeError):
    """The distributed runtime could not start: the coordinator, processes and cause named."""


def initialize(coordinator_address: Optional[str] = None, num_processes: Optional[int] = None,
               process_id: Optional[int] = None, *, timeout_s: int = 300, cpu_collectives: str = "gloo") -> None:
    """Joins this process to the run (`jax.distributed.initialize`); see the module docstring.

    Args:
        coordinator_address: "host:port" of process 0's coordinator service.
        num_processes, process_id: the run's size and this process's rank.
        timeout_s: how long to wait for every process to join.
        cpu_collectives: the CPU collectives implementation ("gloo"; "mpi" where JAX has it).

    Raises:
        DistributedInitError: the coordinator was not reached, or not every process joined, in time.
        ValueError: a partial set of torchrun-style variables, or a bad rank or size.
    """
    if coordinator_address is None and num_processes is None and process_id is None:
        present = [name for name in TORCHRUN_VARIABLES if name in os.environ]
        if present and len(present) != len(TORCHRUN_VARIABLES):
            missing = sorted(set(TORCHRUN_VARIABLES) - set(present))
            raise ValueError(f"torchrun-style launch variables set in part: {', '.join(present)} without "
                             f"{', '.join(missing)}")
        if present:
            coordinator_address = f"{os.environ['MASTER_ADDR']}:{os.environ['MASTER_PORT']}"
            num_processes, process_id = int(os.environ["WORLD_SIZE"]), int(os.environ["RANK"])
    if num_processes is not None and (num_processes < 1 or process_id is None
                                      or not 0 <= process_id < num_processes):
        raise ValueError(f"process_id must be in 0..num_processes - 1, got process_id={process_id}, "
                         f"num_processes={num_processes}")
    if coordinator_address is not None and process_id not in (None, 0):
        _wait_for_coordinator(coordinator_address, timeout_s, process_id, num_processes)
    jax.config.update("jax_cpu_collectives_implementation", cpu_collectives)
    try:
        jax.distributed.initialize(coordinator_address, num_processes, process_id,
                                   initialization_timeout=timeout_s)
    except Exception as exc:  # XLA's DEADLINE_EXCEEDED and connection errors, as JaxRuntimeError/RuntimeError
        where = coordinator_address or "the address JAX detected from the cluster's variables"
        raise DistributedInitError(
            f"process {process_id} of {num_processes} could not join the run coordinated at {where} within "
            f"{timeout_s} s: is process 0 running, reachable there, and are all {num_processes} processes "
            f"started? ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})") from exc


def _wait_for_coordinator(address: str, timeout_s: float, process_id, num_processes) -> None:
    """Returns once a TCP connection to `address` opens; raises DistributedInitError after `timeout_s`."""
    host, _, port = address.rpartition(":")
    if not host or not port.isdigit():
        raise ValueError(f"coordinator_address must be 'host:port', got {address!r}")
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            with socket.create_connection((host.strip("[]"), int(port)), timeout=1.0):
                return
        except OSError as exc:
            if time.monotonic() >= deadline:
                raise DistributedInitError(
                    f"process {process_id} of {num_processes} could not reach the coordinator at {address} "
                    f"within {timeout_s} s ({exc}): is process 0 running and reachable there?") from None
            time.sleep(0.2)
