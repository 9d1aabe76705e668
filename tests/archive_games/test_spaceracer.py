"""Space Racer: the race ends on time, and a player that dodges stars scores crossings."""

import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy


def _pixels(screen):
    cols = jnp.arange(64)
    return (screen[:, cols // 32] >> (31 - cols % 32).astype(jnp.uint32)) & 1


def _dodge(state, key):
    """Climbs while the rows just above ship 1 (x 23) are clear of stars, backs off from stars close on its right."""
    y = state.machine.V[8].astype(jnp.int32)  # ship1y
    px = _pixels(state.machine.screen)
    rows, cols = jnp.arange(32)[:, None], jnp.arange(64)[None, :]
    ahead = (rows >= y - 3) & (rows < y) & (cols >= 22) & (cols < 30)
    beside = (rows >= y) & (rows < y + 3) & (cols >= 26) & (cols < 30)
    blocked = jnp.sum(jnp.where(ahead, px, 0)) > 0
    threat = jnp.sum(jnp.where(beside, px, 0)) > 0
    return jnp.where(~blocked, 1, jnp.where(threat, 2, 0))


def test_a_dodging_player_scores_and_the_race_ends():
    played = play("SpaceRacer", _dodge, steps=2800, num_envs=1)
    assert played.episodes_ended == 1
    assert played.rewards.min() >= 0 and played.rewards.max() == 1  # one crossing at a time
    assert played.returns()[0] >= 5


def test_random_play_ends_on_time_without_negative_rewards():
    played = play("SpaceRacer", random_policy(3), steps=2800, num_envs=2)
    assert played.episodes_ended == 2
    assert played.rewards.min() >= 0 and played.rewards.max() <= 1
