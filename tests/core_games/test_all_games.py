"""Every game of the octax and ours suites: the registry holds the paper's ids and our own games',
each passes the env contract suite, and each level family member survives random play (the
per-group files and test_own_games.py cover the rest). The archive suite: test_archive_suite.py."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.env.testing import check_env

PAPER_IDS = (
    ["Airplane", "Blinky", "Brix", "Deep8", "Filter", "FlightRunner", "Missile", "Pong", "Rocket",
     "ShootingStars", "Spacejam", "Squash", "Submarine", "Tank", "Tetris", "UFO", "VerticalBrix",
     "WipeOff", "Worm"]
    + [f"Cavern{i}" for i in range(1, 8)]
    + [f"SpaceFlight{i}" for i in range(1, 11)]
    + [f"TargetShooter{i}" for i in range(1, 4)]
)
# Our own games (roms/*.8o), each in three levels plus the plain id (its middle level).
OWN_IDS = ["Cycles", "Cycles1", "Cycles2", "Cycles3", "Dodge", "Dodge1", "Dodge2", "Dodge3", "Duel", "Flak", "Flak1",
           "Flak2", "Flak3"]
EXPECTED_IDS = sorted(PAPER_IDS + OWN_IDS)
# test_games_levels.py plays Cavern1, SpaceFlight1 and TargetShooter1 at random; these are the others.
OTHER_LEVELS = [g for g in EXPECTED_IDS if g.startswith(("Cavern", "SpaceFlight", "TargetShooter"))
                and g not in ("Cavern1", "SpaceFlight1", "TargetShooter1")]


def test_registry_holds_exactly_the_suites():
    archive = octax_core.list_games(suite="archive")
    assert octax_core.list_games() == sorted(EXPECTED_IDS + archive)
    assert not set(archive) & set(EXPECTED_IDS)


def test_suites_split_the_registry():
    from octax_core.env import SUITES, suite_of

    assert octax_core.list_games(suite="octax") == sorted(PAPER_IDS)
    assert octax_core.list_games(suite="ours") == OWN_IDS
    assert list(SUITES) == ["octax", "ours", "archive"]
    assert sorted(g for suite in SUITES for g in octax_core.list_games(suite)) == octax_core.list_games()
    assert suite_of("Pong") == "octax" and suite_of("Flak2") == "ours" and suite_of("SuperPong") == "archive"
    with pytest.raises(ValueError, match="unknown suite 'atari'; valid suites: 'octax', 'ours', 'archive'"):
        octax_core.list_games(suite="atari")
    with pytest.raises(KeyError, match="unknown game 'Pacman'"):
        suite_of("Pacman")


def test_specs_are_complete():
    for game_id in EXPECTED_IDS:
        spec = octax_core.get_spec(game_id)
        assert spec.id == game_id and spec.description and spec.title
        assert len(spec.rom_sha1) == 40 and spec.rom_file.endswith(".ch8")
        assert spec.quirks in ("chip8", "schip"), f"{game_id}: quirks {spec.quirks!r}"


# make test runs the contract on three games: an octax game with the VIP's quirks (Pong), one with
# SUPER-CHIP's (Blinky), and one of ours, a two-player game played solo (Duel), whose one-player
# env is the most unlike the others'. The contract's checks (shapes, dtypes, determinism, batch
# independence, one trace, refused actions) are the Env's; what a game brings to them (its score,
# lives and end, its keys) every other id gets in make test-slow (6-10 s of compiles each: Dodge,
# one of ours with Pong's quirks, is one of them), and in make test from the per-game files
# (test_games_group*.py, test_games_levels.py, test_own_games.py: random play, finite rewards).
CONTRACT_IN_MAKE_TEST = {"Pong", "Blinky", "Duel"}


@pytest.mark.parametrize("game_id", [g if g in CONTRACT_IN_MAKE_TEST else pytest.param(g, marks=pytest.mark.slow)
                                     for g in EXPECTED_IDS])
def test_contract(game_id, octax_rom_dir):
    """In 2 envs (env 0 of the batch plays what it plays alone), but for Blinky and Duel in make
    test: one env, the batch of one being also the env run alone, so check_env compiles one step
    for them, not two; Pong's batch check is make test's on CHIP-8."""
    check_env(game_id, num_envs=1 if game_id in ("Blinky", "Duel") else 2, steps=3)


# test_games_levels.py plays level 1 of each family at random through the env; here level 2 of
# each in make test, every other level in make test-slow: 16 envs x 1,500 uniform random steps per
# level, all the levels of a run in one compiled mix (each env plays exactly what make(level)
# plays: tests/core_env/test_mix.py).
FAST_LEVELS = ["Cavern2", "SpaceFlight2", "TargetShooter2"]


@pytest.mark.parametrize("levels", [FAST_LEVELS, pytest.param([g for g in OTHER_LEVELS if g not in FAST_LEVELS],
                                                              marks=pytest.mark.slow)],
                         ids=["level2", "other-levels"])
def test_random_policy_gives_finite_rewards(levels, octax_rom_dir):
    env, params = octax_core.make_mix(levels)
    num_envs, steps = 16, 1500
    games = np.repeat(np.arange(len(levels)), num_envs)
    keys = jax.random.split(jax.random.key(0), num_envs)[np.tile(np.arange(num_envs), len(levels))]
    actions = np.concatenate([np.random.default_rng(0).integers(0, len(octax_core.get_spec(g).action_keys) + 1,
                                                                (steps, num_envs), dtype=np.int32) for g in levels], 1)
    step_keys = jax.random.split(jax.random.key(1), (steps, num_envs))[:, np.tile(np.arange(num_envs), len(levels))]
    step = jax.vmap(env.step, in_axes=(0, 0, 0, None))

    @jax.jit
    def returns(keys, games, actions, step_keys):
        _, state = jax.vmap(lambda k, g: env.reset(k, params, game=g))(keys, games)
        def body(state, xs):
            _, state, reward, *_ = step(xs[1], state, xs[0], params)
            return state, reward
        return jax.lax.scan(body, state, (actions, step_keys))[1].sum(0)

    total = np.asarray(returns(keys, jnp.asarray(games), jnp.asarray(actions), step_keys))
    for g, game_id in enumerate(levels):
        assert np.all(np.isfinite(total[games == g])), f"{game_id}: returns {total[games == g]}"


def test_docs_games_table_is_current():
    import runpy
    from pathlib import Path

    docs = Path(__file__).resolve().parents[2] / "docs"
    table = runpy.run_path(str(docs / "games_table.py"))["games_table"]()
    assert table in (docs / "games.md").read_text(), "docs/games.md is stale: run python docs/games_table.py"
