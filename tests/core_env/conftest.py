"""Fixtures shared by the files of this folder: Cycles' two-player env, mirror off and on, each
with its jitted reset and step, built once per session.

Each compiled program that runs the machine costs seconds on a cold cache, so the tests that
play Cycles (test_mirror.py, test_players.py) step one env at a time through these two steps
(one env, unbatched), however many games they play and whoever chooses the actions.
"""

from __future__ import annotations

import jax
import pytest

import octax_core


@pytest.fixture(scope="session")
def cycles():
    """{mirror: (env, params, reset, step)} for `make_multi("Cycles", mirror=mirror)`; reset and
    step are `jax.jit(env.reset)` and `jax.jit(env.step)`, for one env."""
    built = {}
    for mirror in (False, True):
        env, params = octax_core.make_multi("Cycles", mirror=mirror)
        built[mirror] = env, params, jax.jit(env.reset), jax.jit(env.step)
    return built
