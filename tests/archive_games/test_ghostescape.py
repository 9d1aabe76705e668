"""Ghost Escape: idle and random play lose quickly, a player that drops on the last segment lasts."""

import jax.numpy as jnp
import numpy as np

from archive_play import constant_policy, play, random_policy


def _drop_when_aligned(state, key):
    """Presses X when the segment's top row lines up with the last segment's (`lst` v8)."""
    V = state.machine.V.astype(jnp.int32)
    return jnp.where(V[4] - 1 == V[8], 1, 0)


def test_idle_and_random_play_lose_with_survival_rewards_only():
    idle = play("GhostEscape", constant_policy(0), steps=200, num_envs=1)
    assert idle.episodes_ended >= 10 and max(idle.returns()) < 30
    rand = play("GhostEscape", random_policy(2), steps=200, num_envs=2)
    assert rand.episodes_ended >= 10
    for played in (idle, rand):
        assert set(np.unique(played.rewards)) <= {0.0, 1.0}
        assert not played.rewards[played.terminated].any()  # the losing step earns nothing


def test_dropping_in_line_survives_much_longer():
    aligned = play("GhostEscape", _drop_when_aligned, steps=400, num_envs=1)
    idle = play("GhostEscape", constant_policy(0), steps=400, num_envs=1)
    assert aligned.episodes_ended >= 1
    assert min(aligned.returns()) > 5 * max(idle.returns())
