"""WDL: green letters and a win score, five wrong guesses end the game."""

import collections

import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy
from octax_core.env.games.spec import ram_value
from octax_core.env.romstore import ARCHIVE_ROM_DIR

E, LEFT, RIGHT, UP, DOWN = 1, 2, 3, 4, 5
KB_TABLES = {UP: 0xBFD, DOWN: 0xC19, LEFT: 0xC35, RIGHT: 0xC51}  # `kb-up`, `kb-dn`, `kb-lf`, `kb-rt`
WORD, ENTER = 0xBF7, 27  # `word`: the answer's letters 0..25; key 27 is enter
WRONG_GUESSES = ("abs", "cup", "dog", "elk", "fry")  # valid words with no letter in common


def _first_moves():
    """first[a][b]: the action that starts a shortest walk on the on-screen keyboard from key a to b."""
    rom = (ARCHIVE_ROM_DIR / "wdl.ch8").read_bytes()
    step = {move: rom[table - 0x200:table - 0x200 + 28] for move, table in KB_TABLES.items()}
    first = np.zeros((28, 28), np.int32)
    for start in range(28):
        seen, queue = {start: None}, collections.deque([start])
        while queue:
            key = queue.popleft()
            for move, table in step.items():
                nxt = table[key]
                if nxt not in seen:
                    seen[nxt] = seen[key] or move
                    queue.append(nxt)
        for goal, move in seen.items():
            first[start, goal] = move or 0
    return jnp.asarray(first)


FIRST = _first_moves()


def _typist(letters_of):
    """Types the word `letters_of(state, guess row)` and enters it: walks to each key, presses E;
    every other step holds nothing, since the ROM acts when a key is released."""
    def policy(state, key):
        m = state.machine
        col = jnp.minimum(m.V[0xB], 3)  # `guess-col`
        target = jnp.where(col == 3, ENTER, letters_of(state, m.V[0xC])[jnp.minimum(col, 2)])
        here = m.V[0xD]  # `kb-current`
        action = jnp.where(here == target, E, FIRST[here, target])
        return jnp.where(state.episode_step % 2 == 0, action, 0)
    return policy


def _answer(state, row):
    return jnp.stack([ram_value(state.machine, WORD + i) for i in range(3)])


def _wrong(state, row):
    table = jnp.asarray([[ord(c) - ord("a") for c in word] for word in WRONG_GUESSES])
    return table[jnp.minimum(row, 4)]


def test_typing_the_answer_wins():
    played = play("WDL", _typist(_answer), steps=260, num_envs=2)
    assert played.episodes_ended >= 2
    for ret in played.returns():
        assert 6 <= ret <= 8  # the answer's 1 to 3 distinct letters turn green, plus the win bonus


def test_five_wrong_guesses_lose():
    played = play("WDL", _typist(_wrong), steps=700, num_envs=2)
    assert played.episodes_ended >= 2
    assert played.rewards.min() >= 0 and played.rewards.max() <= 3
    assert all(ret <= 3 for ret in played.returns())  # no win: only green letters score


def test_random_play_never_scores_a_negative_reward():
    played = play("WDL", random_policy(7), steps=500, num_envs=2)
    assert played.rewards.min() >= 0 and played.rewards.max() <= 1
