"""Spacejam! (the archive's): random flights score, lose their three ships and end; holding one key
never gets past the between-turns screen."""

import numpy as np

from archive_play import constant_policy, play, random_policy


def test_random_play_scores_and_uses_up_three_ships():
    played = play("SpacejamArchive", random_policy(5), steps=1500, num_envs=4)
    assert played.episodes_ended >= 8 and min(played.returns()) >= 3  # +1 per turn started, 3 turns
    assert played.rewards.min() == 0 and played.rewards.max() <= 7
    assert set(np.unique(played.lives)) == {0, 1, 2, 3}


def test_a_held_key_waits_on_the_title():
    played = play("SpacejamArchive", constant_policy(1), steps=200, num_envs=1)
    assert played.episodes_ended == 0 and played.rewards.sum() == 0
