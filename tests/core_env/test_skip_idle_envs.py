"""Every registered game plays the same with skip_idle on and off: every observation, reward,
flag and info value of a random-action rollout (with same-step autoreset, so episode ends and
resets are inside it) must match bit for bit, from the same seed.

`make test` checks one game of each platform, among the cheapest to compile of their platform's
games: Pong (CHIP-8 with the VIP's display wait), DodgeArchive (SUPER-CHIP, 1000 instructions a
frame, no start-up to run) and Civiliz8n (XO-CHIP at 100, both planes lit); the whole registry is
marked slow (CI runs it). skip_idle takes effect from `idle.SKIP_FROM` instructions per frame,
so a game whose own rate is lower (the octax suite's 11) plays here at four times its rate: the
same code, with the skipping path on. A game at its own rate skips idle by default, so its
skipping rollout is `make(game, autoreset=True)`'s: Civiliz8n's is the program
test_compiler_options.py checks (tests/core_shared.py).
"""

import jax
import numpy as np
import pytest
from core_shared import ROLLOUT_ENVS, ROLLOUT_STEPS, env_rollout

import octax_core
from octax_core.emulator import idle
from octax_core.env.config import make_config

FAST_GAMES = ["Pong", "DodgeArchive", "Civiliz8n"]
SLOW_GAMES = [g for g in octax_core.list_games() if g not in FAST_GAMES]


def rollout(game: str, skip_idle: bool):
    """(env, params, jitted rollout) of `game` with autoreset, skip_idle on or off, at its own
    instructions per frame or four times a rate under `idle.SKIP_FROM`."""
    own = make_config(octax_core.get_spec(game))[0].instructions_per_frame
    faster = {} if own >= idle.SKIP_FROM else dict(instructions_per_frame=4 * own)
    return env_rollout(game, autoreset=True, skip_idle=skip_idle, **faster)


def check_same_trajectory(game: str):
    env, _, skipping = rollout(game, True)
    plain, _, looping = rollout(game, False)
    assert env.machine.skipping and not plain.machine.skip_idle
    assert env.machine.instructions_per_frame == plain.machine.instructions_per_frame
    keys = jax.random.split(jax.random.key(3), (ROLLOUT_STEPS + 1, ROLLOUT_ENVS))
    actions = np.random.default_rng(7).integers(0, env.num_actions, (ROLLOUT_STEPS, ROLLOUT_ENVS), dtype=np.int32)
    a, b = skipping(keys, actions), looping(keys, actions)
    names = ["reset obs", "obs", "reward", "terminated", "truncated", "info", "final state"]
    for name, x, y in zip(names, [a[0], *a[1], a[2]], [b[0], *b[1], b[2]]):
        for (path, p), q in zip(jax.tree_util.tree_flatten_with_path(x)[0], jax.tree.leaves(y)):
            assert np.array_equal(np.asarray(p), np.asarray(q)), f"{game}: {name}{jax.tree_util.keystr(path)} differs"


@pytest.mark.parametrize("game", FAST_GAMES)
def test_skip_idle_gives_the_same_trajectory(game, octax_rom_dir):
    check_same_trajectory(game)


@pytest.mark.slow
@pytest.mark.parametrize("game", SLOW_GAMES)
def test_skip_idle_gives_the_same_trajectory_on_every_game(game, octax_rom_dir):
    check_same_trajectory(game)


def test_skip_idle_is_an_env_option():
    env, _ = octax_core.make("Snek", skip_idle=False)
    assert env.config.skip_idle is False and env.machine.skip_idle is False
    env, _ = octax_core.make("Snek")
    assert env.config.skip_idle is True and env.machine.skip_idle is True
    with pytest.raises((TypeError, ValueError), match="skip_idle"):
        octax_core.make("Snek", skip_idle=3)
