"""Mastermind: a player who reads the answer wins at the first guess (reward 11); one who submits
the same random code eleven times loses (reward 0); random play never loses reward."""

import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy
from octax_core.env.games.spec import in_routine, ram_value

ANSWER, GUESSES = 0x202, 0x206  # `answer_code`, `guesses` (4 bytes a column)
CHOOSE_PEGS = (0x925, 0xA05)  # `choose_pegs` and the `get_keypress` it calls
NEXT, DOWN, START, SUBMIT, RANDOM = 1, 3, 3, 5, 6


def _between_turns(state):
    """Outside `choose_pegs` (title, rules, refused-guess page): key 8 every other step, so that
    each FX0A sees it released."""
    return jnp.where(state.episode_step % 2 == 0, START, 0)


def _cheat(state, key):
    """Sets each row of the first column to the answer's symbol, then submits."""
    machine = state.machine
    column, row = machine.V[13].astype(jnp.int32), machine.V[10].astype(jnp.int32)
    wrong = jnp.array([ram_value(machine, GUESSES + column * 4 + r) != ram_value(machine, ANSWER + r)
                       for r in range(4)])
    action = jnp.where(wrong[row], NEXT, jnp.where(wrong.any(), DOWN, SUBMIT))
    return jnp.where(in_routine(machine, *CHOOSE_PEGS), action, _between_turns(state))


def _stubborn(state, key):
    """A random first code (key D), then submits it (key F) every time: 11 guesses, no win unless
    the random code is the answer."""
    action = jnp.where(state.episode_step % 4 < 2, RANDOM, SUBMIT)
    return jnp.where(in_routine(state.machine, *CHOOSE_PEGS), action, _between_turns(state))


def test_reading_the_answer_wins_at_the_first_guess():
    played = play("Mastermind", _cheat, steps=300, num_envs=2)
    assert played.episodes_ended >= 2
    for env in range(2):
        first_end = int(np.argmax(played.terminated[:, env]))
        assert played.rewards[: first_end + 1, env].sum() == 11 and played.rewards[:, env].min() == 0


def test_eleven_stubborn_guesses_lose():
    played = play("Mastermind", _stubborn, steps=500, num_envs=2)
    assert played.episodes_ended >= 2 and (played.rewards == 0).all()


def test_random_play_never_loses_reward():
    played = play("Mastermind", random_policy(7), steps=1000, num_envs=2)
    assert (played.rewards >= 0).all() and (played.score >= 0).all()
