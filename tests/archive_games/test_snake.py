"""Snake: a greedy player eats (+1 each, never a jump at the end) and dies on its tail; random play ends too."""

import jax.numpy as jnp

from archive_play import play, random_policy

UP, LEFT, DOWN, RIGHT = 1, 2, 3, 4


def _greedy(state, key):
    """Straight for the food (V7, V8) from the head (VA, VB): columns first, then rows. The first
    step holds no key: the title's FX0A completes when the start-up's key 9 is released."""
    V = state.machine.V.astype(jnp.int32)
    head_x, head_y, food_x, food_y = V[10], V[11], V[7], V[8]
    horizontal = jnp.where(food_x > head_x, RIGHT, LEFT)
    vertical = jnp.where(food_y > head_y, DOWN, UP)
    move = jnp.where(food_x != head_x, horizontal, jnp.where(food_y != head_y, vertical, 0))
    return jnp.where(state.episode_step == 0, 0, move)


def test_a_greedy_player_eats_and_dies_on_its_tail():
    played = play("Snake", _greedy, steps=1500, num_envs=2)
    assert played.rewards.sum() >= 20
    assert set(played.rewards.ravel()) <= {0.0, 1.0}
    assert played.episodes_ended >= 1


def test_random_play_ends_episodes_without_negative_rewards():
    played = play("Snake", random_policy(5), steps=800, num_envs=2)
    assert played.episodes_ended >= 4 and played.rewards.min() == 0
