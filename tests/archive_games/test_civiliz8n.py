"""Civiliz8n: random play places tiles, scores and ends games; holding one key is one press."""

import numpy as np

from archive_play import constant_policy, play, random_policy


def test_random_play_scores_every_game_and_ends_it():
    played = play("Civiliz8n", random_policy(10), steps=400, num_envs=4)
    returns = played.returns()
    assert played.episodes_ended >= 8 and min(returns) >= 5  # every finished game placed tiles
    assert (played.rewards >= 0).all() and played.rewards.max() <= 20  # one turn's points at a time


def test_a_held_key_is_one_press():
    """Key 1 held forever selects the first tile once and places nothing: no score, no end."""
    played = play("Civiliz8n", constant_policy(1), steps=100, num_envs=1)
    assert played.rewards.sum() == 0 and played.episodes_ended == 0
    assert np.all(played.score == 0)
