"""Mastermind (Octojam 3, archive "mastermind"): deduce the hidden code of four symbols in 11 guesses.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the MASTER MIND header; up to 11 columns of guesses
(four 3x3 symbols out of 8, one column per guess), over each played column its clues (a 4x4 box
with 0..4 black marks: right symbol in the right row; 2x2 white marks: right symbol in another
row); the column in play under an arrow with a blinking selector on one row; the hooded answer on
the right.

### Actions
0: no-op, 1: key 9 (Octo's D: next symbol in the selected row), 2: key 7 (A: previous symbol),
3: key 8 (S: next row down; also starts the game from the title), 4: key 5 (W: row up), 5: key F
(V: submit the column), 6: key D (R: a random code of four different symbols, first column
only). `get_keypress` polls the held keys every 6 frames (`pause`), so a key held for a step
counts once at most and may not count at all. (Key C, Octo's 4, which shows the pages of rules,
is not offered; a key other than 8 on the title also pages through them, as the ROM does.)

### Reward
On a win, 12 minus the guesses used; nothing for a loss. That is 11 for the first guess, 1 for the
eleventh (the ROM shows the count next to its happy face). It is read from the clues the ROM
keeps, `black_clues` (0x232, one byte per column, which `check_4_win` writes as each guess is
scored): the first column with 4 black marks, c (0-based), scores 11 - c; the registers
(`black_count` v8, `play_column` vd) are reused or rewritten by the end-of-game drawing. A guess
that repeats a symbol is refused (`check_guess_code`: a page that waits for a key) and not
counted.

### Termination
The game over, won or lost: `main` leaves its loop when a guess scores 4 black marks or the 11th
is scored, and draws the answer, the happy or sad face and ten flashes, then waits for a key
(FX0A at 0xD21) before `jump main`; the pc in 0xC93..0xD24 or a routine called from there is the
end.

Options from the archive: tickrate 20, Octo's default quirks, its colours. Start-up: none.
`init` draws the answer (`pick_random_answer`, `random`) before the title waits for its key, so
any start-up past the title would fix the answer for every episode; instead each episode starts
at boot, the answer is drawn from its reset key, and the agent starts the game with key 8
(released: the title's FX0A; another key pages through the rules, which end at the last page or
at key 8).
Episodes are cut at 4,500 steps (5 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, ram_value

BLACK_CLUES = 0x232  # `black_clues`: black marks per column, 11 columns
COLUMNS = 11
THE_END = (0xC93, 0xD25)  # `main` after its loop, up to `jump main`


def _won(state):
    """11 - c for the first column c whose guess scored 4 black marks; 0 while none has."""
    score = jnp.int32(0)
    for column in reversed(range(COLUMNS)):  # the earliest win is the one that counts
        score = jnp.where(ram_value(state, BLACK_CLUES + column) == 4, COLUMNS - column, score)
    return score


SPECS = (archive_spec(
    "mastermind",
    id="Mastermind",
    rom_sha1="898ef1505c874065697ffc6cba688367e143d82e",
    action_keys=(9, 7, 8, 5, 0xF, 0xD),
    score_fn=_won,
    terminated_fn=lambda state: in_routine(state, *THE_END),
    max_episode_steps=4500,
    category="planning",
    description="Deduce the hidden code of four different symbols out of eight: pick each row's "
                "symbol (keys 9/7 next and previous, 8/5 row down and up; 8 also starts the game), "
                "submit with key F (key D: a random first guess) and read the clues; reward 12 "
                "minus the guesses used on a win, 0 on a loss; the game ends when the code is "
                "guessed or after 11 guesses.",
),)
