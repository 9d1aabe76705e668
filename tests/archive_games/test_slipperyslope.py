"""Slippery Slope: random play solves the first level now and then; replaying a solution of every
level (found by a breadth-first search over the archive's level data) reaches THE END."""

import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy
from octax_core.env.games.spec import ram_value

# Per level, the slides that solve it (0 right, 1 up, 2 left, 3 down: action = slide + 1).
SOLUTIONS = [[2, 3, 2, 1, 0, 1, 0, 3, 0, 1, 0, 3], [1, 0, 1, 2, 3, 2, 1, 2, 3, 2, 1], [0, 0, 3, 2, 1],
             [0, 3, 0, 0, 1], [3], [0, 0, 3, 0], [0, 3, 2, 2, 2, 1, 3, 0], [0, 3, 1, 0, 3], [0, 2, 2, 2],
             [2, 3, 0, 3, 3]]
TABLE = jnp.array([s + [0] * (12 - len(s)) for s in SOLUTIONS])


def _steps(machine, address):
    """A step counter of the ROM: two bytes, hundreds and units (0..99 each)."""
    return ram_value(machine, address) * 100 + ram_value(machine, address + 1)


def _solver(state, key):
    """Slides as the solution says whenever the game waits for input (pmode vA 0) or shows the
    next level's card (pmode 2, which any slide key leaves); idle while a slide goes on."""
    machine = state.machine
    level = machine.V[6].astype(jnp.int32)
    moves = _steps(machine, 0x204) - _steps(machine, 0x202)  # `step-level` - `step-total`
    slide = TABLE[jnp.clip(level - 1, 0, 9), jnp.clip(moves, 0, 11)]
    mode = machine.V[10]
    return jnp.where((mode == 0) | (mode == 2), slide + 1, 0)


def test_the_solutions_reach_the_end_one_level_at_a_time():
    played = play("SlipperySlope", _solver, steps=700, num_envs=1)
    assert played.episodes_ended >= 1
    first_end = int(np.argmax(played.terminated[:, 0]))
    rewards = played.rewards[: first_end + 1, 0]
    assert rewards.sum() == 10 and set(rewards) == {0.0, 1.0}


def test_random_play_never_loses_reward_and_sometimes_solves_level_one():
    played = play("SlipperySlope", random_policy(5), steps=1500, num_envs=2)
    assert played.episodes_ended == 0  # no game over: only the tenth level ends it
    assert (played.rewards >= 0).all() and played.rewards.max() <= 1
    assert played.rewards.sum() >= 1  # level 1 (walls only) falls to a random walk
