"""Snake (Octojam 1, archive "snake"): classic Snake without walls, in SUPER-CHIP lores.

### Observation
The screen, uint8 (frames_per_step, 64, 128): the 64x32 lores playfield (each pixel a 2x2 block)
with the snake and one food dot; the snake wraps around the edges.

### Actions
0: no-op, 1: key 5 (up), 2: key 7 (left), 3: key 8 (down), 4: key 9 (right) (`W_KEY`, `A_KEY`,
`S_KEY`, `D_KEY`); the snake cannot reverse into itself.

### Reward
+1 per food eaten. The ROM's length `len` (VD, `:alias len vd`) starts at 4, `generate-food`
adds 1 for every food placed (the first at start), and `gameover` takes 5 back (`len += -5`) to
show the food eaten; the score is `len - 5` while playing and `len` once `gameover` has
subtracted, so the reward never jumps at the end.

### Termination
The head running into the tail: `gameover` (0x64E) draws GAME OVER, the score and the high score
(kept in the SUPER-CHIP flag registers), then waits for a key with FX0A (0x69C), whose release
would restart; any step that ends inside it (or in a subroutine it called) ends the episode.

Options from the archive: SUPER-CHIP, tickrate 15, Octo's default quirks, its own colours; the
snake moves once per main-loop pass (no delay timer), so its speed is the tickrate's. Start-up:
200 frames (the title, drawn string by string, reaches its FX0A after 194), then key 9 held 2
frames for that "wait for first direction", which completes when the first env step releases it
(the snake starts moving right; a policy that holds key 9 from the first step stays on the
title until it lets go). The first food is placed before the title, so it is the same in every
episode; every later one (`random`) is drawn from the episode's reset key. Episodes are cut at
4,500 steps (5 minutes).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, register_value

LEN = 13  # VD
GAME_OVER = (0x64E, 0x69E)  # `gameover` up to and including its FX0A
SUBTRACTED = 0x652  # after `len += -5`


def _score(state):
    subtracted = in_routine(state, SUBTRACTED, GAME_OVER[1])
    length = register_value(state, LEN)
    return length - 5 * (1 - subtracted.astype(length.dtype))


SPECS = (archive_spec(
    "snake",
    id="Snake",
    rom_sha1="06a6692c92eb8077329b6d4e59d55479d60574a8",
    action_keys=(5, 7, 8, 9),
    score_fn=_score,
    terminated_fn=lambda state: in_routine(state, *GAME_OVER),
    startup=((0, 200), (key_mask(9), 2)),
    max_episode_steps=4500,
    category="planning",
    description="Steer the snake (keys 5 up, 7 left, 8 down, 9 right) to eat food; reward +1 per "
                "food; the game ends when the head hits the tail.",
),)
