"""Flutter By: a butterfly that only sinks runs out of energy; random flights find some nectar,
and live longer, but run out too."""

import numpy as np

from archive_play import constant_policy, play, random_policy


def test_a_sinking_butterfly_runs_out_of_energy():
    played = play("FlutterBy", constant_policy(2), steps=2000, num_envs=1)
    assert played.episodes_ended == 1 and set(played.rewards.ravel()) == {0.0, 1.0}
    assert 1500 < played.returns()[0] < 2000  # 64 scrolls, no nectar at the bottom


def test_random_flights_find_nectar_and_still_end():
    played = play("FlutterBy", random_policy(3), steps=2600, num_envs=2)
    assert played.episodes_ended >= 1 and np.all(played.rewards >= 0) and played.rewards.max() == 1
    ended = played.terminated.any(axis=0)
    lengths = np.argmax(played.terminated, axis=0)[ended] + 1
    assert lengths.max() > 2000  # outlives the sinking butterfly: it reached flowers
