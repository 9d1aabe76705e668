"""Danm8ku: random ships sometimes outlast a pattern phase, and are always hit in the end."""

from archive_play import play, random_policy


def test_random_play_survives_a_phase_now_and_then_and_is_hit():
    played = play("Danm8ku", random_policy(5), steps=600, num_envs=2)
    assert played.episodes_ended >= 20
    assert played.rewards.sum() >= 2 and set(played.rewards.ravel()) == {0.0, 1.0}
    lengths = 600 * 2 / played.episodes_ended
    assert lengths > 20  # a phase is 255 ticks (64 steps); nobody dies at once
