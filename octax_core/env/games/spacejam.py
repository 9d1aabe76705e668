"""Spacejam! (William Donnelly, Octojam 2, 2015; octax's build without intro/end screens): fly a
ship through a scrolling cave past star-shaped obstacles.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the ship, a jagged ceiling and floor scrolling
left, an obstacle now and then; the score and ships left flash up between turns.

### Actions
0: no-op, 1: key 5 (up), 2: key 8 (down), 3: key 7 (left), 4: key 9 (right).

### Reward
Change of V9, the score: +1 per turn started (1 at reset; the third turn's comes after the end),
+3 per obstacle passed, +1 every 50 game ticks and +6 every 100 (when the game speeds up).

### Termination
VA (ships left) == 0, the paper's rule. VA counts ships still in the hangar (3, minus one as each
turn starts), so this ends as the third ship takes off; the ROM starts a new game a few
instructions after the last crash, so no later state marks the end.

Quirks "schip": an Octo game (community database: modernChip8). Under "chip8" the VIP's flag
reset zeroes VF after `vf &= v0`, the cave-width test before placing an obstacle, so no obstacle
ever appears after the first one of a turn.
Timers: real 60 Hz. The game was tuned for 100 instructions per frame (the database's tickrate):
there it waits on the delay timer between ticks, and freezing the timers (as octax does) would
double its speed. At the default 11 a tick outlasts the wait, so the timers change nothing, but
the game runs about 9 times slower than designed (the ship moves once per ~11 steps);
`make("Spacejam", instructions_per_frame=100)` plays it at its intended speed.
Start-up: 32 frames (octax: 300 instructions = 28, which stops short of the first turn's
last line, `score += 1`), the cave drawn and the first turn under way. Episodes are cut at
4,500 steps (5 minutes); random play ends in 250 to 650.
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

SPECS = (GameSpec(
    id="Spacejam",
    title="Spacejam!",
    rom_file="spacejam.ch8",
    rom_sha1="8d7fd91cefb8dcbd9faa270e6f39fbab73713f5b",
    action_keys=(5, 8, 7, 9),
    score_fn=lambda state: state.V[9].astype(jnp.int32),
    terminated_fn=lambda state: state.V[10] == 0,
    lives_fn=lambda state: state.V[10].astype(jnp.int32),
    startup=((0, 32),),
    quirks="schip",
    max_episode_steps=4500,
    category="navigation",
    description="Fly a ship (keys 5/8 up/down, 7/9 left/right) through a scrolling cave and past "
                "obstacles; reward is the change of V9 (points for turns, obstacles passed and time); "
                "the game ends as the last of 3 ships takes off (VA == 0).",
),)
