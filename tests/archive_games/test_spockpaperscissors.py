"""Spock Paper Scissors: every round's reward follows the game's rules, random play scores both
ways, and episodes (the game has no end) are only cut."""

import jax
import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy
from octax_core.emulator.state import NO_KEY
from octax_core.env import make

TURN_USER_KEY = 0x57E  # `turn_user`'s FX0A
ROCK, PAPER, SCISSORS, LIZARD, SPOCK = 1, 2, 3, 4, 5  # `move_user` / `move_cpu` values = actions
BEATS = {ROCK: {LIZARD, SCISSORS}, PAPER: {SPOCK, ROCK}, SCISSORS: {LIZARD, PAPER},
         LIZARD: {SPOCK, PAPER}, SPOCK: {SCISSORS, ROCK}}


def _every_hand_in_turn(steps, num_envs=2):
    """Throws rock, paper, scissors, lizard, Spock, rock, ... (one key press per FX0A wait, let go
    the next step) and records each step's reward and the two throws (V6, V7)."""
    env, params = make("SpockPaperScissors", autoreset=True)

    def one(carry, key):
        state, thrown = carry
        machine = state.machine
        ready = (machine.pc == TURN_USER_KEY) & (machine.key_wait == NO_KEY)
        action = jnp.where(ready, thrown % 5 + 1, 0)
        _, state, reward, terminated, truncated, _ = env.step(key, state, action, params)
        return (state, thrown + ready), (reward, terminated, state.machine.V[6], state.machine.V[7])

    @jax.jit
    def run(keys):
        def single(key):
            _, state = env.reset(key, params)
            keys = jax.random.split(key, steps)
            return jax.lax.scan(one, (state, jnp.int32(0)), keys)[1]
        return jax.vmap(single)(keys)

    return [np.asarray(x) for x in run(jax.random.split(jax.random.key(3), num_envs))]


def test_every_round_is_scored_by_the_rules():
    rewards, terminated, user, cpu = _every_hand_in_turn(800)
    scored = rewards != 0
    assert scored.sum() >= 40  # about 40 rounds per env, 4 in 5 decided
    for r, u, c in zip(rewards[scored], user[scored], cpu[scored]):
        assert r == (1 if c in BEATS[u] else -1 if u in BEATS[c] else 0), (r, u, c)
    assert set(user[scored]) == {1, 2, 3, 4, 5} and set(cpu[scored]) == {1, 2, 3, 4, 5}
    assert (rewards == 1).any() and (rewards == -1).any() and not terminated.any()


def test_random_play_scores_both_ways_and_is_only_cut():
    played = play("SpockPaperScissors", random_policy(6), steps=900, num_envs=2, max_episode_steps=300)
    assert set(np.unique(played.rewards)) == {-1.0, 0.0, 1.0}
    assert played.episodes_ended == 0 and played.truncated.sum() == 6  # cut at 300, 600, 900 steps
    assert len(played.returns()) == 6
