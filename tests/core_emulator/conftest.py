"""Fixtures for the core tests: the per-opcode `chip` builder (see chip_builder.py), and the
batched twin of tests/conftest.py's `jit_run_frames`, shared by the files of this folder."""

import functools

import jax
import pytest
from chip_builder import chip  # noqa: F401  (a pytest fixture, used by test_ops_*.py)

import octax_core


@functools.lru_cache(maxsize=None)
def jitted_batch_run_frames(machine: octax_core.Machine, frames: int):
    """`machine.run_frames` over a batch (states and keys batched, `frames` frames), with the
    platform's compiler options: one compile per (machine, frames, batch size) for the session.
    Tests of a file that need a batched machine share it by using one config and frame count."""
    return jax.jit(jax.vmap(lambda state, keys: machine.run_frames(state, keys, frames)),
                   compiler_options=machine.compiler_options)


@pytest.fixture(scope="session")
def jit_batch_run_frames():
    return jitted_batch_run_frames
