"""Carbon8: slabs complete under random play, and a thermostat on the power bar earns the full verdict."""

import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy


def _thermostat(state, key):
    """Raises the cooling power (key 9) while `temp_ex` (vC) is below 80, lowers it (key 8) above 110."""
    temp_ex = state.machine.V[12].astype(jnp.int32)
    return jnp.where(temp_ex < 80, 3, jnp.where(temp_ex > 110, 4, 0))


def test_random_play_completes_slabs_with_verdicts_only_at_the_end():
    played = play("Carbon8", random_policy(7), steps=1000, num_envs=2)
    assert played.episodes_ended >= 2
    assert set(np.unique(played.rewards)) <= {0.0, 1.0, 2.0}
    assert not (played.rewards[~played.terminated] != 0).any()  # the verdict comes with the end only


def test_a_thermostat_hits_both_goals():
    played = play("Carbon8", _thermostat, steps=1000, num_envs=1)
    assert played.episodes_ended == 1
    assert played.returns()[0] == 2
