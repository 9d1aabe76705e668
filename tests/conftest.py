"""Shared fixtures: where the ROMs are, and jitted machine functions compiled once per session.

JAX compiles are the slow part of this suite, so every test that runs a `Machine` goes through
these caches: one compile per (machine config, function) for the whole session.
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

import jax
import pytest

import octax_core

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
TEST_SUITE_DIR = SHARED / "roms" / "test-suite"
# Tests read the third-party ROMs from ../shared (never from git); `make test` sets this too.
os.environ.setdefault("OCTAX_ROM_DIR", str(SHARED / "roms" / "octax"))
OCTAX_ROM_DIR = Path(os.environ["OCTAX_ROM_DIR"]).resolve()


@functools.lru_cache(maxsize=None)
def jitted_run_frames(machine: octax_core.Machine):
    """`machine.run_frames` jitted with `frames` static; one compile per (machine, frames)."""
    return jax.jit(machine.run_frames, static_argnums=2)


@functools.lru_cache(maxsize=None)
def jitted_execute(machine: octax_core.Machine):
    """`machine.execute` (one instruction) jitted; one compile per machine."""
    return jax.jit(machine.execute)


@pytest.fixture(scope="session")
def jit_run_frames():
    return jitted_run_frames


@pytest.fixture(scope="session")
def jit_execute():
    return jitted_execute


@pytest.fixture(scope="session")
def counter_rom(tmp_path_factory) -> Path:
    """The Counter test game (tests/counter_game.py) as a ROM file, written once per session.

    Envs of one (game, config, ROM) share one compiled program (octax_gym caches it), so tests
    that build envs with the same keywords pay for the compile once per worker.
    """
    from counter_game import COUNTER_ROM

    path = tmp_path_factory.mktemp("counter") / "counter.ch8"
    path.write_bytes(COUNTER_ROM)
    return path


@pytest.fixture(scope="session")
def test_suite_dir() -> Path:
    if not TEST_SUITE_DIR.is_dir():
        pytest.fail(f"the CHIP-8 test suite is missing: expected {TEST_SUITE_DIR} (../shared beside the repo)")
    return TEST_SUITE_DIR


@pytest.fixture(scope="session")
def octax_rom_dir() -> Path:
    if not OCTAX_ROM_DIR.is_dir():
        pytest.fail(f"game ROMs missing: expected {OCTAX_ROM_DIR}; set OCTAX_ROM_DIR=../shared/roms/octax")
    return OCTAX_ROM_DIR
