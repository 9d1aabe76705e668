"""The long tail of `make_mix`'s exactness: every one-player game of the registry, each platform's
games in one mix, plays step for step what `make(game)` plays (slow: a compile per game)."""

from __future__ import annotations

import jax
import numpy as np
import pytest

import octax_core

pytestmark = pytest.mark.slow

STEPS = 25
OPTIONS = dict(noop_max=2, repeat_action_probability=0.25)
BY_PLATFORM = {platform: [g for g in octax_core.list_games() if octax_core.get_spec(g).platform == platform]
               for platform in ("chip8", "schip", "xochip")}


def _rollout(env, params, key, num_actions, game=None):
    obs, state = env.reset(key, params) if game is None else env.reset(key, params, game=game)

    def one(carry, _):
        state, key = carry
        key, action_key, step_key = jax.random.split(key, 3)
        action = jax.random.randint(action_key, (), 0, num_actions)
        obs, state, reward, terminated, truncated, info = env.step(step_key, state, action, params)
        return (state, key), (obs, reward, terminated, truncated, info["score"], info["lives"])

    return obs, jax.lax.scan(one, (state, key), None, length=STEPS)[1]


@pytest.fixture(scope="module", params=sorted(BY_PLATFORM))
def platform_mix(request):
    games = BY_PLATFORM[request.param]
    env, params = octax_core.make_mix(games, **OPTIONS)
    rollouts = jax.jit(jax.vmap(lambda k, n, g: _rollout(env, params, k, n, g), in_axes=(0, None, None)))
    return games, rollouts


def test_every_game_in_its_platforms_mix_plays_what_make_plays(platform_mix):
    games, rollouts = platform_mix
    keys = jax.random.split(jax.random.key(5), 2)
    for index, game in enumerate(games):
        single, params = octax_core.make(game, **OPTIONS)
        expected = jax.jit(jax.vmap(lambda k: _rollout(single, params, k, single.num_actions)))(keys)
        got = rollouts(keys, single.num_actions, index)
        for want, have in zip(jax.tree.leaves(expected), jax.tree.leaves(got)):
            np.testing.assert_array_equal(want, have, err_msg=game)
