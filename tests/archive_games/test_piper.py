"""Piper: random flight collects goodies and gets caught by waves; a bird that always hides is never caught."""

from archive_play import constant_policy, play, random_policy


def test_random_play_collects_goodies_and_waves_end_it():
    played = play("Piper", random_policy(6), steps=1500, num_envs=4)
    assert played.episodes_ended >= 20 and played.rewards.sum() >= 40
    assert played.rewards.min() == 0 and played.rewards.max() <= 5


def test_a_hidden_bird_survives_and_scores_nothing():
    played = play("Piper", constant_policy(1), steps=600, num_envs=2)
    assert played.episodes_ended == 0 and played.rewards.sum() == 0
