"""Every registered game plays the same with skip_idle on and off: every observation, reward,
flag and info value of a random-action rollout (with same-step autoreset, so episode ends and
resets are inside it) must match bit for bit, from the same seed.

`make test` checks one game of each platform (Pong with the VIP's display wait, DodgeArchive,
OctoPartyMix, the archive's busiest); the whole registry is marked slow (CI runs it). skip_idle
takes effect from `idle.SKIP_FROM` instructions per frame, so a game whose own rate is lower (the
octax suite's 11) plays here at four times its rate: the same code, with the skipping path on.
"""

import functools

import jax
import numpy as np
import pytest

import octax_core
from octax_core.emulator import idle
from octax_core.env.config import make_config

NUM_ENVS = 2
STEPS = 40
FAST_GAMES = ["Pong", "DodgeArchive", "OctoPartyMix"]
SLOW_GAMES = [g for g in octax_core.list_games() if g not in FAST_GAMES]


def make_env(game: str, skip_idle: bool):
    own = make_config(octax_core.get_spec(game))[0].instructions_per_frame
    ipf = own if own >= idle.SKIP_FROM else 4 * own
    return octax_core.make(game, autoreset=True, skip_idle=skip_idle, instructions_per_frame=ipf)


def rollout(env, params, key, actions):
    """NUM_ENVS envs reset from `key`, then STEPS steps of `actions`: first obs, trajectory, final state."""
    obs, state = jax.vmap(env.reset, in_axes=(0, None))(jax.random.split(key, NUM_ENVS), params)

    def step(carry, inputs):
        state, = carry
        keys, action = inputs
        out = jax.vmap(env.step, in_axes=(0, 0, 0, None))(keys, state, action, params)
        obs, state, reward, terminated, truncated, info = out
        return (state,), (obs, reward, terminated, truncated, info)

    keys = jax.random.split(jax.random.fold_in(key, 1), (STEPS, NUM_ENVS))
    (state,), trajectory = jax.lax.scan(step, (state,), (keys, actions))
    return obs, trajectory, state


# One entry: a game's two rollouts, skip_idle on and off, are one compiled program (a compile
# per game, not two). Keeping every game's programs alive through the whole-registry slow test
# grew a worker past what CI's machine holds.
@functools.lru_cache(maxsize=1)
def rollouts(game: str):
    """The game's envs with skip_idle on and off, and both rollouts of a key and actions, jitted as one."""
    fast, slow = make_env(game, True), make_env(game, False)
    return fast[0], slow[0], jax.jit(lambda key, actions: (rollout(*fast, key, actions), rollout(*slow, key, actions)))


def check_same_trajectory(game: str):
    env, plain, both = rollouts(game)
    assert env.machine.skip_idle and not plain.machine.skip_idle
    actions = np.random.default_rng(7).integers(0, env.num_actions, (STEPS, NUM_ENVS), dtype=np.int32)
    a, b = both(jax.random.key(3), actions)
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
