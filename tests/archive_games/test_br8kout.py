"""Br8kout: bricks break and misses end the game, under random play and a paddle that follows the ball."""

import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy


def test_random_play_breaks_bricks_and_misses():
    played = play("Br8kout", random_policy(3), steps=400, num_envs=2)
    assert played.episodes_ended >= 2
    assert set(np.unique(played.rewards)) <= {0.0, 1.0}  # one brick at a time; the miss takes none back
    assert played.rewards.sum() >= 1


def _follow_the_ball(state, key):
    """Keeps the paddle's middle under the ball's column (both wrap around the 64-pixel screen)."""
    V = state.machine.V.astype(jnp.int32)
    gap = (V[11] - (V[13] + 3)) % 64  # ballx - paddle middle, 0..63
    gap = jnp.where(gap >= 32, gap - 64, gap)
    return jnp.where(gap < -1, 1, jnp.where(gap > 1, 2, 0))


def test_a_paddle_that_follows_the_ball_breaks_more_and_misses_less():
    followed = play("Br8kout", _follow_the_ball, steps=400, num_envs=2)
    random = play("Br8kout", random_policy(3), steps=400, num_envs=2)
    assert followed.rewards.sum() > 2 * random.rewards.sum() > 0
    assert followed.episodes_ended < random.episodes_ended
    assert set(np.unique(followed.rewards)) <= {0.0, 1.0}
