"""WDL (Octojam 9, archive "wdl"): guess the hidden three-letter word in five tries (Wordle).

### Observation
The screen, uint8 (frames_per_step, 32, 64): up to five rows of three-letter guesses, each letter
marked (outlined: right letter, right place; dotted: in the word elsewhere; underlined: not in
it), and an on-screen keyboard (A..Z, delete, enter) with a blinking cursor; letters known to be
absent vanish from it, letters found turn solid.

### Actions
0: no-op, 1: key 6 (Octo E: press the key under the cursor: type a letter, delete, or enter a
complete guess; on the title, start the round), 2: key 7 (cursor left, A), 3: key 9 (right, D),
4: key 5 (up, W), 5: key 8 (down, S), 6: key 4 (delete the last letter, Q). The ROM acts when a
key is released (`debounce`), so a repeated action is one press.

### Reward
+1 per letter first placed in its right spot, +5 per word solved. The game keeps no score, so the
reward follows its feedback: +1 for each letter first placed in
its right spot (the ROM sets its byte in `found`, 0xBDB, 26 bytes, cleared by `init`), and +5
for solving the word (while `game-win`, 0x548, runs). A solved word has earned 1 to 3 green
letters, so a round returns 6 to 8 when won, at most 3 when lost. Guesses that are not in the
512-word list are refused (buzzer) and cost nothing.

### Termination
The round ends: `game-win` (0x548, "you win") after a right guess, or `game-lose` (0x56E, "was"
and the answer) after the fifth wrong one; both wait on FX0A then `jump init`, and the episode
ends there (0x548..0x59D, with the routines they call).

Options from the archive: tickrate 15 with the VIP quirks it was made for (clip, vblank, logic).
The title (`intro`) never waits on FX0A: `iwait` polls key E and jumps straight to `init`, which
draws the answer (`random` into `wordlist`). So the start-up only lets the title animate (150
frames, no key) and the episode begins on the title: the agent's first key 6 starts the round,
so each episode's word comes from its reset key. `init` takes longer than a step, so that press
types nothing. Episodes are cut at 4,500 steps (5 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, ram_value

FOUND = 0xBDB  # `found`: one byte per letter A..Z (then delete, enter), 1 once placed right
GAME_WIN = (0x548, 0x56E)  # `game-win`, up to `game-lose`
GAME_OVER = (0x548, 0x59E)  # `game-win` and `game-lose`, up to the title's word data `w1`
WIN_BONUS = 5


def _score(state):
    """Letters found in their right place, plus WIN_BONUS while the win screen shows."""
    found = sum(ram_value(state, FOUND + letter) for letter in range(26))
    return found + WIN_BONUS * in_routine(state, *GAME_WIN).astype(jnp.int32)


SPECS = (archive_spec(
    "wdl",
    id="WDL",
    rom_sha1="a8d6e9b1976c99ddc0c4818828a6d3cb3ae6f348",
    action_keys=(6, 7, 9, 5, 8, 4),
    score_fn=_score,
    terminated_fn=lambda state: in_routine(state, *GAME_OVER),
    startup=((0, 150),),
    max_episode_steps=4500,
    category="planning",
    description="Guess the hidden three-letter word in five tries: move the keyboard cursor "
                "with keys 7/9/5/8, type and enter with key 6, delete with key 4 (key 6 also starts "
                "the round on the title); reward +1 per letter first placed right and +5 for "
                "solving; the round ends when it is solved or after the fifth wrong guess.",
),)
