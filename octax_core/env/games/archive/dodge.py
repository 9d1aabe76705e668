"""Dodge (Octojam 8, archive "dodge"): an asteroid-dodging shmup in 56 bytes of SUPER-CHIP.

Not our own Dodge (`Dodge`, suite "ours"); hence the id `DodgeArchive`.

### Observation
The screen, uint8 (frames_per_step, 64, 128): the ship (5x3) near the bottom of the 64x32 lores
screen and rocks falling in from the top as the whole screen scrolls down 4 pixels a move.

### Actions
0: no-op, 1: key 7 (Octo's A: left), 2: key 9 (D: right); 3 pixels a move.

### Reward
+1 for every step the ship survives after (`survival_reward`): the program keeps no score (it
fits in 56 bytes), and dodging is the whole game.

### Termination
A rock touching the ship (VF after drawing it): the loop ends at FX0A (0x226), which waits for
a key and then restarts; a step that ends there ends the episode.

Options from the archive: SUPER-CHIP (for `scroll-down`), tickrate 1000, Octo's default quirks,
its colours. A move every 6 frames (the delay timer; `registers` sets the pace). Start-up: none;
every rock's column (`random 63`) is drawn from each episode's reset key. The ROM spends nearly
all of its 1,000 instructions a frame waiting on the delay timer, which makes it one of the
slowest games to emulate here (see docs/gallery.md). Episodes are cut at 4,500 steps (5 minutes).
"""

from octax_core.env.games.archive._program import archive_spec

WAIT_KEY = 0x226  # the FX0A after the game loop

SPECS = (archive_spec(
    "dodge",
    id="DodgeArchive",
    rom_sha1="7fb69647e6b10e2b12f9357d5c1c177349028236",
    action_keys=(7, 9),
    score_fn=lambda state: 0,
    survival_reward=1.0,
    terminated_fn=lambda state: state.pc == WAIT_KEY,
    max_episode_steps=4500,
    category="reaction",
    description="Move the ship (keys 7 left, 9 right) to dodge the falling rocks; reward +1 per step "
                "survived (the 56-byte ROM keeps no score); the game ends when a rock hits the ship.",
),)
