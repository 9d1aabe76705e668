"""Masquer8: levels are scored and the shark ends the game, under random play and a scripted player."""

import jax
import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy

KEY_WAIT = 0x264  # `v-key := key` in the main loop (shipped ROM)


def test_random_play_scores_and_ends():
    played = play("Masquer8", random_policy(17), steps=500, num_envs=2)
    assert played.episodes_ended >= 2
    assert set(np.unique(played.rewards)) <= {0.0, 1.0}  # one level at a time, never negative
    assert played.rewards.sum() >= 1


def _solve_level_one(state, key):
    """Level 1's puzzle is one stripe pattern (key 2 in the shipped ROM): toggle it, then blend in with V (key F); on
    level 2 the same moves fail until the shark arrives. Every other step holds no key,
    so that each FX0A sees its key released."""
    machine = state.machine
    # At the move's FX0A after the first move (Moves, VA, is reused elsewhere): action 1 holds key F;
    # anywhere else action 3 holds key 2, which also passes the text screens.
    wanted = jnp.where((machine.pc == KEY_WAIT) & (machine.V[0xA] > 0), 1, 3)
    return jnp.where(jax.random.bernoulli(key), wanted, 0)


def test_a_player_that_solves_level_one_scores_every_episode():
    played = play("Masquer8", _solve_level_one, steps=300, num_envs=2)
    assert played.episodes_ended >= 2
    assert all(ret == 1 for ret in played.returns()[:played.episodes_ended])
