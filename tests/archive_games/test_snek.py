"""Snek: one step's survival earns 1; turning back onto the trail ends it at once, circling does later."""

import jax.numpy as jnp
import numpy as np

from archive_play import constant_policy, play, random_policy

RIGHT, UP, LEFT, DOWN = 1, 2, 3, 4


def test_random_play_runs_into_the_trail():
    played = play("Snek", random_policy(5), steps=500, num_envs=2)
    assert played.episodes_ended >= 50 and set(played.rewards.ravel()) == {0.0, 1.0}


def test_going_straight_wraps_around_into_the_trail():
    """Right forever: the head wraps at x 64 and meets its own trail after one lap."""
    played = play("Snek", constant_policy(RIGHT), steps=300, num_envs=1)
    ends = np.flatnonzero(played.terminated[:, 0])
    assert len(ends) >= 2 and np.all(np.diff(ends) == np.diff(ends)[0])  # the same lap every episode


def test_a_square_spiral_outlives_random_play():
    def spiral(state, key):
        return jnp.array([RIGHT, DOWN, LEFT, UP])[(state.episode_step // 9) % 4]
    steered = play("Snek", spiral, steps=300, num_envs=1)
    random = play("Snek", random_policy(5), steps=300, num_envs=1)
    assert np.mean(steered.returns() or [300]) > np.mean(random.returns())
