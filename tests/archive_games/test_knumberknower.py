"""Knumber Knower: random and idle play lose, a player that reads the ROM's answer never does."""

import jax.numpy as jnp
import numpy as np

from archive_play import constant_policy, play, random_policy


def _knower(state, key):
    """Presses the key for `answer` (vA: 0 equal, 1 top smaller, 2 top greater) every other step."""
    answer = state.machine.V[10]
    act = jnp.where(answer == 2, 1, jnp.where(answer == 0, 2, 3))
    return jnp.where(state.episode_step % 2 == 0, act, 0)  # the answer counts on release


def test_random_and_idle_play_end_with_unit_rewards():
    rand = play("KnumberKnower", random_policy(4), steps=600, num_envs=2)
    assert rand.episodes_ended >= 20 and rand.rewards.sum() >= 5
    idle = play("KnumberKnower", constant_policy(0), steps=300, num_envs=1)
    assert idle.episodes_ended >= 5 and idle.rewards.sum() == 0  # the timer runs out
    for played in (rand, idle):
        assert played.rewards.min() >= 0 and played.rewards.max() <= 1


def test_knowing_the_answer_scores_every_question():
    played = play("KnumberKnower", _knower, steps=600, num_envs=1)
    assert played.episodes_ended == 0
    assert played.rewards.sum() >= 25
    assert np.all(played.rewards <= 1)
