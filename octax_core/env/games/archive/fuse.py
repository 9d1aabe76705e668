"""Fuse (Octojam 3, archive "fuse"): lay line tiles ahead of a burning fuse to keep it burning.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the lines laid so far (one pixel wide), the fuse's
spark (a blinking dot) at the end of its trail, and the cursor: the next 8x8 line tile, which
follows the cursor keys.

### Actions
0: no-op, 1: key 5 (cursor up, Octo W), 2: key 8 (down, S), 3: key 7 (left, A), 4: key 9
(right, D), 5: key 6 (lay the tile, E; it is laid when the key is released, and only where it
overlaps no line; the next tile is drawn at random). No key restarts the game during play.

### Reward
+1 per pixel the fuse burns: the change of the ROM's score, `:alias timer-1 v7` (low two
digits) plus 100 x `:alias timer-2 v6` (high digits), which `move-fuse` (0x27C) increments every
`fuse-speed` (3) turns of the main loop, i.e. 10 pixels every 3 seconds. While `show-score`
(0x2D6..0x2EB) shows the last game's score the score counts as 0 (see start-up), so it never
jumps.

### Termination
The fuse finds no line to follow: `move-fuse` falls through into `game-over` (0x2C6..0x2D5),
which blinks the spark until key 6 is pressed and released; the episode ends there.

Options from the archive: tickrate 15, Octo's default quirks; the main loop waits 6 frames a turn.
`init-game` draws the fuse's start (position and direction) and the first tile before the title,
so the start-up plays one throwaway game: 20 frames of title, key 6 pressed to start, 600 frames
for the untouched fuse to burn out, key 6 pressed and released on `game-over`, then key 6 held on
`show-score`'s FX0A. The first step's release runs `init-game` again, so each episode's start and
tiles come from its reset key. Episodes are cut at 4,500 steps (5 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, register_value

GAME_OVER = (0x2C6, 0x2D6)  # `game-over`, its two key loops
SHOW_SCORE = (0x2D6, 0x2EC)  # `show-score`: the last game's score, then FX0A and `init-game`


def _score(state):
    """`timer-2` x 100 + `timer-1`; 0 while the start-up's throwaway game shows its score."""
    burnt = register_value(state, 6) * 100 + register_value(state, 7)
    return jnp.where((state.pc >= SHOW_SCORE[0]) & (state.pc < SHOW_SCORE[1]), 0, burnt)


SPECS = (archive_spec(
    "fuse",
    id="Fuse",
    rom_sha1="0cd895dc3d489d0e40656218900a04310e95f560",
    action_keys=(5, 8, 7, 9, 6),
    score_fn=_score,
    terminated_fn=lambda state: in_routine(state, *GAME_OVER),
    startup=((0, 20), (key_mask(6), 2), (0, 600), (key_mask(6), 2), (0, 4), (key_mask(6), 2)),
    max_episode_steps=4500,
    category="planning",
    description="Move the line tile (keys 5/8 up and down, 7/9 left and right) and lay it with "
                "key 6 so the burning fuse always has a line to follow; reward +1 per pixel "
                "burnt; the game ends when the fuse burns out.",
),)
