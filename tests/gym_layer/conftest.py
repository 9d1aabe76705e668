"""Fixtures for the Gymnasium-layer tests: the Counter test game as a ROM file.

Envs of one (game, config, ROM) share one compiled program (octax_gym.program caches it), so
tests that build envs with the same keywords pay for the compile once per worker.
"""

from __future__ import annotations

import pytest

from counter_game import COUNTER_ROM


@pytest.fixture(scope="session")
def counter_rom(tmp_path_factory):
    path = tmp_path_factory.mktemp("counter") / "counter.ch8"
    path.write_bytes(COUNTER_ROM)
    return path
