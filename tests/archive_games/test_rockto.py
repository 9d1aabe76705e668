"""Rockto: diamonds and the exit score, a falling boulder ends the game."""

import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy

KEY_WAIT = 0x6F0  # `dir := key` in `move-player`
LEFT, RIGHT, UP, DOWN = 1, 2, 3, 4

# Level 1's solution: (player x, y, diamonds left) -> move. Up the diamond column at x 7, back
# down, right to the diamond under the boulder at x 10, out from under it before it falls, up and
# back left for the diamond that fell, then right and down to the exit.
SOLUTION = {
    (2, 3, 4): RIGHT, (3, 3, 4): RIGHT, (4, 3, 4): RIGHT, (5, 3, 4): RIGHT, (6, 3, 4): RIGHT,
    (7, 3, 4): UP, (7, 2, 3): UP, (7, 1, 2): DOWN, (7, 2, 2): DOWN, (7, 3, 2): RIGHT,
    (8, 3, 2): RIGHT, (9, 3, 2): RIGHT, (10, 3, 1): RIGHT, (11, 3, 1): UP, (11, 2, 1): LEFT,
    (10, 2, 0): RIGHT, (11, 2, 0): RIGHT, (12, 2, 0): RIGHT, (13, 2, 0): DOWN,
}


def _solve_level_one(state, key):
    """Presses the solution's move when `move-player` waits for a key, and releases otherwise; on
    level 2 it finds no move, holds nothing and plays out the step budget."""
    m = state.machine
    x, y, left = m.V[8], m.V[9], m.V[0xA]
    move = sum(jnp.where((x == a) & (y == b) & (left == d), act, 0) for (a, b, d), act in SOLUTION.items())
    fresh = (m.pc == KEY_WAIT) & (m.key_wait == 0xFF)
    return jnp.where(fresh & (m.V[0xB] == 1), move, 0)


def test_solving_level_one_scores_every_diamond_and_the_exit():
    played = play("Rockto", _solve_level_one, steps=200, num_envs=1)
    rewards = played.rewards[:, 0]
    assert rewards.sum() == 4 + 5  # four diamonds, then the exit bonus
    assert set(np.unique(rewards)) == {0.0, 1.0, 5.0}
    assert played.episodes_ended == 0


def test_random_play_scores_and_ends():
    played = play("Rockto", random_policy(5), steps=1500, num_envs=2)
    assert played.episodes_ended >= 1
    assert played.rewards.min() >= 0 and played.rewards.max() <= 5
    assert played.rewards.sum() >= 1
