"""The long tail of `make_mix`'s exactness: every one-player game of the registry, each platform's
games in one mix, plays step for step what `make(game)` plays (slow: a compile per game)."""

from __future__ import annotations

import jax
import numpy as np
import pytest

import octax_core

from random_rollouts import random_rollout

pytestmark = pytest.mark.slow

STEPS = 25
OPTIONS = dict(noop_max=2, repeat_action_probability=0.25)
BY_PLATFORM = {platform: [g for g in octax_core.list_games() if octax_core.get_spec(g).platform == platform]
               for platform in ("chip8", "schip", "xochip")}


@pytest.fixture(scope="module", params=sorted(BY_PLATFORM))
def platform_mix(request):
    games = BY_PLATFORM[request.param]
    env, params = octax_core.make_mix(games, **OPTIONS)
    rollouts = jax.jit(jax.vmap(lambda k, n, g: random_rollout(env, params, k, n, STEPS, g), in_axes=(0, None, None)))
    return games, rollouts


def test_every_game_in_its_platforms_mix_plays_what_make_plays(platform_mix):
    games, rollouts = platform_mix
    keys = jax.random.split(jax.random.key(5), 2)
    for index, game in enumerate(games):
        single, params = octax_core.make(game, **OPTIONS)
        expected = jax.jit(jax.vmap(lambda k: random_rollout(single, params, k, single.num_actions, STEPS)))(keys)
        got = rollouts(keys, single.num_actions, index)
        for want, have in zip(jax.tree.leaves(expected), jax.tree.leaves(got)):
            np.testing.assert_array_equal(want, have, err_msg=game)
