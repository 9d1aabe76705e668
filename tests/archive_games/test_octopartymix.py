"""Octo Party Mix!: random play reaches rounds (+1 each), loses lives and ends."""

import numpy as np

from archive_play import play, random_policy


def test_random_play_scores_rounds_loses_lives_and_ends():
    played = play("OctoPartyMix", random_policy(6), steps=600, num_envs=2)
    assert played.episodes_ended >= 1
    assert set(np.unique(played.rewards)) == {0.0, 1.0}  # one round at a time, never negative
    assert min(played.returns()) >= 4  # four lives: at least four rounds reached
    assert {4, 3, 2, 1} <= set(np.unique(played.lives))
