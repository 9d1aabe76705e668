"""Into the GarlicScape: health falls and the episode ends under random play; the score reads
`player-score` (checked through the source's debug key 2, which adds a point and is not offered
to agents: random play rarely reaches an alium)."""

import dataclasses

import numpy as np

import octax_core
from archive_play import constant_policy, play, random_policy


def test_random_play_loses_health_and_the_episode_ends():
    played = play("IntoTheGarlicScape", random_policy(5), steps=400, num_envs=4)
    assert played.episodes_ended >= 1
    assert set(np.unique(played.lives)) >= {3, 2, 1}  # each hit takes a heart
    assert (played.rewards >= 0).all()


def test_the_score_is_player_score():
    spec = octax_core.get_spec("IntoTheGarlicScape")
    debug = dataclasses.replace(spec, action_keys=(2,))  # the source's debug key: TRANSITION_ADD_SCORE
    played = play(debug, constant_policy(1), steps=12, num_envs=1)
    assert played.rewards.max() == 1 and played.rewards.sum() >= 2 and (played.rewards >= 0).all()
    assert list(played.score[:, 0]) == sorted(played.score[:, 0])
