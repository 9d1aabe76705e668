"""Flight Runner (the archive's): every step flown earns 1, the crash step nothing, and crashes end it."""

import numpy as np

from archive_play import constant_policy, play, random_policy


def _lengths(played):
    ended = played.terminated | played.truncated
    return [int(t) + 1 for t in np.flatnonzero(ended[:, 0])]


def test_random_flights_crash_and_return_their_length():
    played = play("FlightRunnerArchive", random_policy(5), steps=1500, num_envs=4)
    assert played.episodes_ended >= 20 and set(played.rewards.ravel()) == {0.0, 1.0}
    assert np.all(played.score == 0)  # the ROM's score: none; the reward is survival
    ends = np.flatnonzero(played.terminated[:, 0])
    assert np.all(played.rewards[ends, 0] == 0)  # the crash step earns nothing
    starts = np.concatenate([[0], ends[:-1] + 1])
    for start, end in zip(starts, ends):
        assert played.rewards[start:end + 1, 0].sum() == end - start  # one per step flown before it


def test_flying_straight_also_crashes():
    played = play("FlightRunnerArchive", constant_policy(0), steps=1200, num_envs=2)
    assert played.episodes_ended >= 2
