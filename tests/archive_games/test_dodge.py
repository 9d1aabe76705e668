"""Dodge (the archive's): random ships survive a while and are hit; standing still is hit too."""

from archive_play import constant_policy, play, random_policy


def test_random_play_survives_then_is_hit():
    played = play("DodgeArchive", random_policy(3), steps=400, num_envs=2)
    assert played.episodes_ended >= 10 and set(played.rewards.ravel()) == {0.0, 1.0}
    assert all(r >= 1 for r in played.returns())


def test_a_still_ship_is_hit_too():
    played = play("DodgeArchive", constant_policy(0), steps=300, num_envs=1)
    assert played.episodes_ended >= 1
