"""Super Octogon: random runs survive a wave or two and are caught by the walls."""

from archive_play import play, random_policy


def test_random_play_survives_waves_and_is_caught():
    played = play("SuperOctogon", random_policy(3), steps=600, num_envs=2)
    assert played.episodes_ended >= 8
    assert played.rewards.sum() >= 5 and set(played.rewards.ravel()) == {0.0, 1.0}
