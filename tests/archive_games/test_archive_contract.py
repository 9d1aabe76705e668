"""The env contract (`octax_core.env.testing.check_env`) on every game of the archive suite, each
at its own platform, quirks and tickrate, from the ROM shipped in the package."""

import pytest

import octax_core
from octax_core.env.testing import check_env


@pytest.mark.parametrize("game_id", octax_core.list_games(suite="archive"))
def test_contract(game_id):
    check_env(game_id, num_envs=2, steps=4)
