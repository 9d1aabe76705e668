"""Sw8 Copter: random taps climb past a 64-pixel mark now and then, and every flight ends."""

from archive_play import play, random_policy


def test_random_play_climbs_and_crashes():
    played = play("Sw8Copter", random_policy(2), steps=800, num_envs=4)
    assert played.episodes_ended >= 50
    assert played.rewards.sum() >= 10 and set(played.rewards.ravel()) <= {0.0, 1.0}
    assert max(played.returns()) >= 1
