"""Fuse: the burning fuse scores, burns out and starts somewhere new each episode."""

import jax
import numpy as np

import octax_core
from archive_play import play, random_policy


def test_random_play_scores_and_ends():
    played = play("Fuse", random_policy(6), steps=400, num_envs=2)
    assert played.episodes_ended >= 4
    assert set(np.unique(played.rewards)) <= {0.0, 1.0}  # one fuse move at a time, never negative
    assert min(played.returns()) >= 5  # the starting trail alone burns for a while


def test_each_episode_draws_its_own_start():
    env, params = octax_core.make("Fuse")
    starts = set()
    for seed in range(4):
        _, state = env.reset(jax.random.key(seed), params)
        _, state, *_ = env.step(jax.random.key(0), state, 0, params)  # releases E: `init-game` runs
        starts.add((int(state.machine.V[0xD]), int(state.machine.V[0xC])))  # fuse x (vd), y (vc)
    assert len(starts) >= 3
