"""Shared fixtures: where the ROMs are, and jitted machine functions compiled once per session.

JAX compiles are the slow part of this suite, so every test that runs a `Machine` goes through
these caches: one compile per (machine config, function) for the whole session. Where the
third-party data comes from, and what happens without ../shared: tests/shared_data.py.
"""

from __future__ import annotations

import collections
import functools
import json
import math
import os
from pathlib import Path

import jax
import pytest

import octax_core

from shared_data import REQUIRE_SHARED, SHARED, TEST_SUITE_DIR, missing_shared, octax_rom_folder
from work_units import work_unit

# Tests read the octax suite's ROMs from ../shared when it is there (never from git), else from
# the user data folder that `octax-gym roms install` fills; `make test` sets this too.
os.environ.setdefault("OCTAX_ROM_DIR", str(SHARED / "roms" / "octax"))

# JAX's persistent compilation cache: most of this suite's time is XLA compiling the same programs
# run after run, so a second run reads them from disk. The cache lives in the clone (.cache/, git
# ignores it); the environment variables reach the CLI and example subprocesses the tests start.
# A compiled program is keyed by its HLO, options and JAX version, so a stale entry is never used.
# Every compile is kept, however short: a test's eager jnp ops (outside any jit) each compile a tiny
# program of 10-50 ms, hundreds per process, and reading them back is cheaper than compiling them.
_JAX_CACHE = os.environ.setdefault("JAX_COMPILATION_CACHE_DIR",
                                   str(Path(__file__).resolve().parent.parent / ".cache" / "jax"))
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")
jax.config.update("jax_compilation_cache_dir", _JAX_CACHE)
jax.config.update("jax_persistent_cache_min_compile_time_secs",
                  float(os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"]))

# Where a cold run's time goes: with OCTAX_COMPILE_LOG=FILE every XLA compile (or persistent-cache
# read), trace and lowering is appended to FILE as a tab-separated line (test, event, function,
# seconds); `python tests/compile_log.py FILE` sums it by file, test and function.
if os.environ.get("OCTAX_COMPILE_LOG"):
    from compile_log import record_compiles

    record_compiles(os.environ["OCTAX_COMPILE_LOG"])


# Longest files first: pytest-xdist hands each worker whole files (`--dist loadfile`) in collection
# order, so a long file collected last keeps one worker busy while the other waits. Each run records
# its files' seconds here (controller only, merged with earlier runs' files) and the next run
# schedules them longest first, new files before all; within a file the order is kept. Files that
# share a session's training runs go to one worker as one unit (tests/work_units.py), ordered by
# their summed seconds.
_FILE_SECONDS = Path(__file__).resolve().parent.parent / ".cache" / "test-file-seconds.json"
_SECONDS_THIS_RUN: collections.Counter = collections.Counter()


def _recorded_file_seconds() -> dict:
    try:
        seconds = json.loads(_FILE_SECONDS.read_text())
    except (OSError, ValueError):
        return {}
    return seconds if isinstance(seconds, dict) else {}


def pytest_configure(config):
    if _recorded_file_seconds() and hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False  # xdist would queue files by test count, not this order


def pytest_xdist_make_scheduler(config, log):
    """`--dist loadfile`, with the files of one `work_units.work_unit` in one unit; any other
    mode is xdist's own."""
    if config.getoption("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class LoadFileWithSharedRuns(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return work_unit(super()._split_scope(nodeid))

    return LoadFileWithSharedRuns(config, log)


def pytest_collection_modifyitems(config, items):
    seconds = _recorded_file_seconds()
    if not seconds:
        return
    first_seen: dict = {}
    for item in items:
        first_seen.setdefault(item.nodeid.split("::")[0], len(first_seen))

    unit_seconds: collections.Counter = collections.Counter()
    for file in first_seen:
        unit_seconds[work_unit(file)] += float(seconds.get(file, math.inf))

    def longest_first(item):  # a unit's files together, at the unit's summed seconds
        file = item.nodeid.split("::")[0]
        return -unit_seconds[work_unit(file)], first_seen[file]

    items.sort(key=longest_first)  # stable: a file's tests keep their order


def pytest_runtest_logreport(report):
    _SECONDS_THIS_RUN[report.nodeid.split("::")[0]] += report.duration


def pytest_sessionfinish(session):
    if hasattr(session.config, "workerinput") or not _SECONDS_THIS_RUN:
        return  # an xdist worker: the controller sees every worker's reports and writes once
    seconds = {**_recorded_file_seconds(), **{f: round(t, 2) for f, t in _SECONDS_THIS_RUN.items()}}
    try:
        _FILE_SECONDS.parent.mkdir(parents=True, exist_ok=True)
        _FILE_SECONDS.write_text(json.dumps(seconds, indent=0, sort_keys=True))
    except OSError:
        pass  # a read-only clone: the order stays the collection's


def pytest_runtest_setup(item):
    """Tests marked `shared` need ../shared: skipped without it, failed if it is required."""
    if item.get_closest_marker("shared") is not None:
        why = missing_shared(SHARED)
        if why is not None:
            if REQUIRE_SHARED:
                pytest.fail(f"{why} (OCTAX_REQUIRE_SHARED=1: this run must have it)")
            pytest.skip(why)


@functools.lru_cache(maxsize=None)
def jitted_run_frames(machine: octax_core.Machine):
    """`machine.run_frames` jitted with `frames` static; one compile per (machine, frames). With the
    platform's compiler options, as octax-gym's own steps compile it (the differential tests
    check the program that ships)."""
    return jax.jit(machine.run_frames, static_argnums=2, compiler_options=machine.compiler_options)


@functools.lru_cache(maxsize=None)
def jitted_execute(machine: octax_core.Machine):
    """`machine.execute` (one instruction) jitted, with the platform's compiler options; one compile per machine."""
    return jax.jit(machine.execute, compiler_options=machine.compiler_options)


@pytest.fixture(scope="session", autouse=True)
def sb3_logs_in_pytest_temp(tmp_path_factory):
    """Stable-Baselines3's `learn` makes a folder for its logger on every call: SB3_LOGDIR, else a new
    /tmp/SB3-<time>. The suite's go under pytest's own temp folder, which pytest prunes, instead of
    piling up in /tmp (the processes the tests start inherit the variable)."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("SB3_LOGDIR", str(tmp_path_factory.mktemp("sb3-logs")))
        yield


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
def two_counters_rom(tmp_path_factory) -> Path:
    """tests/two_player_games.py's TwoCounters (a simultaneous two-player game) as a ROM file."""
    from two_player_games import TWO_COUNTERS_ROM

    path = tmp_path_factory.mktemp("two_counters") / "two_counters.ch8"
    path.write_bytes(TWO_COUNTERS_ROM)
    return path


@pytest.fixture(scope="session")
def take_turns_rom(tmp_path_factory) -> Path:
    """tests/two_player_games.py's TakeTurns (a turn-based two-player game) as a ROM file."""
    from two_player_games import TAKE_TURNS_ROM

    path = tmp_path_factory.mktemp("take_turns") / "take_turns.ch8"
    path.write_bytes(TAKE_TURNS_ROM)
    return path


@pytest.fixture(scope="session")
def test_suite_dir() -> Path:
    """The Timendus test suite in ../shared (tests using it are marked `shared` too)."""
    why = missing_shared(TEST_SUITE_DIR)
    if why is not None:
        if REQUIRE_SHARED:
            pytest.fail(why)
        pytest.skip(why)
    return TEST_SUITE_DIR


@pytest.fixture(scope="session")
def octax_rom_dir() -> Path:
    """The folder with every third-party game's ROM (OCTAX_ROM_DIR, or the user data folder)."""
    folder = octax_rom_folder()
    if folder is None:
        pytest.fail("the octax suite's ROMs are missing: neither OCTAX_ROM_DIR "
                    f"({os.environ.get('OCTAX_ROM_DIR')}) nor the user data folder holds them all; "
                    "run `octax-gym roms install` (make test does)")
    return folder
