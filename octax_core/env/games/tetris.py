"""Tetris (Fran Dachille, 1991): stack falling pieces into full lines.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the well in the middle, the falling piece, and
the line count on the right once a line is cleared.

### Actions
0: no-op, 1: key 4 (rotate), 2: key 5 (left), 3: key 6 (right), 4: key 7 (drop faster).

### Reward
Change of V10, the lines cleared: +1 per line.

### Termination
V1 equals 2: V1 is the falling piece's row, which starts at 3, so 2 means a new piece collided
where it appears (the well is full). The ROM has no game-over screen; it would go on spawning
pieces there.

Quirks "chip8": written for CHIP-48 and listed for every profile (community database: chip48,
originalChip8, modernChip8); the quirks that differ do not change its logic (no shift or BNNN;
VF after 8XY2 and I after FX55/FX65 are never read), so the profile only sets the VIP's
display-wait pacing. Timers: real 60 Hz; a piece falls one row per 16 frames of delay timer (2
frames fewer at lines 4, 12, 20, ...), and frozen timers would make it fall one row per step.
Start-up: 75 frames (octax: 300 instructions = 28), until the well is drawn; V1 passes 2 while
the well is drawn, so the start-up must not stop earlier. The first piece is drawn from the
reset key. Episodes are cut at 9,000 steps (10 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

SPECS = (GameSpec(
    id="Tetris",
    title="Tetris",
    rom_file="Tetris [Fran Dachille, 1991].ch8",
    rom_sha1="5f518084744bf3cb8733f6e5454dfd1634320563",
    action_keys=(4, 5, 6, 7),
    score_fn=lambda state: state.V[10].astype(jnp.int32),
    terminated_fn=lambda state: state.V[1] == 2,
    startup=((0, 75),),
    quirks="chip8",
    max_episode_steps=9000,
    category="planning",
    description="Rotate (key 4), move (keys 5 left, 6 right) and drop (key 7) the falling pieces; "
                "reward +1 per line cleared; the game ends when a new piece has no room.",
),)
