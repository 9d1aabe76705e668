"""Sens8tion: kills pay and the story ends, under random play and a shooter that aims at the antagonists."""

import jax
import jax.numpy as jnp
import numpy as np

from archive_play import constant_policy, play, random_policy
from octax_core.env.games.spec import ram_value

ENEMY_DATA = 0x1B0  # `enemyDataArea`: 4 bytes per zone, the second the character drawn there
ZONE_KEYS = (1, 2, 3, 4, 6, 7, 8, 9)  # zone 0..7 -> its key (key 5 is the cleric's own square)


def test_random_play_kills_and_reaches_the_end():
    played = play("Sens8tion", random_policy(10), steps=2500, num_envs=2)
    assert played.episodes_ended >= 2  # the story's end (00FD), without a game over to reach first
    assert played.rewards.min() >= 0 and played.rewards.max() <= 3  # kills, a few per round at most
    assert played.returns()[:2] == [136.0, 136.0]  # every battle's quota, then the unscored boss


def _aim(state, key):
    """Shoots a zone holding a live trooper or katana man (character 0x01..0x40), else a random key."""
    characters = jnp.stack([ram_value(state.machine, ENEMY_DATA + 4 * zone + 1) for zone in range(8)])
    live = (characters >= 1) & (characters <= 0x40)
    pick = jax.random.categorical(key, jnp.where(live, 0.0, -jnp.inf))
    return jnp.where(live.any(), jnp.asarray(ZONE_KEYS)[pick], jax.random.randint(key, (), 1, 10))


def test_an_aiming_shooter_ends_the_story_and_no_keys_stay_in_the_cutscene():
    aimed = play("Sens8tion", _aim, steps=2200, num_envs=2)
    assert aimed.terminated.any(axis=0).all()
    assert aimed.returns()[:2] == [136.0, 136.0]
    assert (np.diff(aimed.score[:1800], axis=0) >= 0).all()  # kills only add up until the end
    idle = play("Sens8tion", constant_policy(0), steps=200, num_envs=1)
    assert idle.rewards.sum() == 0 and idle.episodes_ended == 0


def test_aiming_clears_the_first_battle_in_fewer_rounds():
    """Antagonists unshot at a round's end leave (the suck bar), so aiming makes the 32 kills sooner."""
    def first_32(policy):
        played = play("Sens8tion", policy, steps=450, num_envs=8, seed=5)
        reached = played.score >= 32
        assert reached.any(axis=0).all()
        return reached.argmax(axis=0).mean()
    assert first_32(_aim) < first_32(random_policy(10)) - 30
