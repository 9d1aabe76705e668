"""Super Pong: the score moves and the game ends, under random play and a scripted player."""

import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy


def test_random_play_scores_and_ends():
    played = play("SuperPong", random_policy(5), steps=600, num_envs=2)
    assert played.episodes_ended >= 2
    assert (played.rewards >= 0).all() and played.rewards.max() == 1  # one hit at a time, never negative
    assert max(played.returns()) >= 1


def _follow_the_ball(state, key):
    """Keeps the paddles on the ball: the vertical pair on its row, the horizontal pair on its column."""
    V = state.machine.V.astype(jnp.int32)
    ball_x, ball_y, paddle_y, paddle_x = V[3], V[4], V[9] + 3, V[10] + 3
    vertical = jnp.where(ball_y < paddle_y, 1, jnp.where(ball_y > paddle_y, 2, 0))
    horizontal = jnp.where(ball_x < paddle_x, 3, jnp.where(ball_x > paddle_x, 4, 0))
    near_side = (ball_x < 8) | (ball_x > 55)  # the ball heads for a vertical paddle: track its row
    return jnp.where(near_side, vertical, horizontal)


def test_a_player_that_follows_the_ball_outscores_random_play():
    followed = play("SuperPong", _follow_the_ball, steps=600, num_envs=2)
    random = play("SuperPong", random_policy(5), steps=600, num_envs=2)
    assert followed.rewards.sum() > 3 * random.rewards.sum() > 0
    assert np.all(followed.rewards >= 0)
