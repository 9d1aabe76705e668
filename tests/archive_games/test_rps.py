"""RPS: random play and a quick thrower win rounds one at a time (carries included), and the
1,000th win, the ROM's only end, ends the episode with the score at 1,000."""

import jax
import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy
from octax_core.emulator.state import NO_KEY
from octax_core.env import make

THROW_KEY = 0x873  # `body`'s FX0A


def _quick_thrower(state, key):
    """Throws rock, paper, scissors in turn whenever `body` waits for a hand (FX0A, no key seen
    yet), and lets go the next step, so every throw counts once."""
    machine = state.machine
    ready = (machine.pc == THROW_KEY) & (machine.key_wait == NO_KEY)
    return jnp.where(ready, 1 + (state.episode_step // 2) % 3, 0)


def test_a_quick_thrower_wins_a_third_of_its_rounds_and_carries_the_digits():
    played = play("RPS", _quick_thrower, steps=2500, num_envs=2)
    assert set(np.unique(played.rewards)) == {0.0, 1.0}  # one win at a time, also across 9 -> 10
    wins = played.rewards.sum(axis=0)
    assert (wins >= 15).all() and (wins <= 60).all()  # about 100 rounds each, a third of them won
    assert (played.score[-1] == wins).all() and played.episodes_ended == 0


def test_random_play_wins_rounds():
    played = play("RPS", random_policy(4), steps=1500, num_envs=2)
    assert set(np.unique(played.rewards)) == {0.0, 1.0}
    assert played.rewards.sum() >= 10 and played.episodes_ended == 0


def test_the_thousandth_win_ends_the_game():
    """From a game at 999 wins (the three digits V2, V1, V0 set to 9 before the battle screen
    draws them), the next win runs the easter egg: the episode ends with the score at 1,000."""
    env, params = make("RPS")

    @jax.jit
    def run(key):
        _, state = env.reset(key, params)
        machine = state.machine
        state = state.replace(machine=machine.replace(V=machine.V.at[:3].set(9)), score=jnp.float32(999))

        def one(state, key):
            action = _quick_thrower(state, key)
            _, state, reward, terminated, truncated, info = env.step(key, state, action, params)
            return state, (reward, terminated, info["score"], state.machine.V[10])
        return jax.lax.scan(one, state, jax.random.split(key, 600))[1]

    rewards, terminated, score, mode = (np.asarray(x) for x in run(jax.random.key(7)))
    end = int(np.argmax(terminated))
    assert terminated.any() and rewards.sum() == 1 and rewards[end] == 1
    assert score[end] == 1000 and (score[:end] == 999).all()
