"""Outlaw: duels end under random play, and a player that aims wins more than random play."""

import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy


def _aim(state, key):
    """Goes to the top (lefty 2, bullet row 7, which clears the cactus) and fires straight."""
    lefty = state.machine.V[13].astype(jnp.int32)
    return jnp.where(lefty > 2, 2, 1)


def test_random_play_ends_duels_with_unit_outcomes():
    played = play("Outlaw", random_policy(6), steps=1000, num_envs=3)
    assert played.episodes_ended >= 6
    assert set(np.unique(played.rewards)) <= {-1.0, 0.0, 1.0}
    # one outcome per duel: every terminal step carries +-1, no other step does
    assert np.all((played.rewards != 0) == played.terminated)


def test_an_aiming_player_wins_duels():
    aimed = play("Outlaw", _aim, steps=1000, num_envs=3)
    random = play("Outlaw", random_policy(6), steps=1000, num_envs=3)
    assert (aimed.rewards == 1).sum() >= 3
    assert aimed.rewards.sum() > random.rewards.sum()
