"""Spacejam! (Octojam 2, archive "spacejam"): fly a ship through a scrolling cave past obstacles.

The archive's original, with its title and end screens; the octax suite's `Spacejam` is a build
without them, played at 11 instructions per frame.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the ship, a jagged ceiling and floor scrolling
left and an obstacle now and then; between turns the SPACE JAM title with the score and the
ships left.

### Actions
0: no-op, 1: key 5 (up), 2: key 8 (down), 3: key 7 (left), 4: key 9 (right). Each turn starts
after a key is pressed and released on the between-turns screen (FX0A in `new_turn`), so a policy
that holds one key forever waits there until the episode is cut.

### Reward
+1 per turn started, +3 per obstacle passed and bonuses over time, the ROM's own score. It is the change
of `score` (V9, `:alias score v9`): +1 per turn started, +3 per obstacle passed, +1
every 50 game ticks and +6 every 100 (when the game speeds up).

### Termination
The last of 3 ships crashing: `main` leaves its loop when `ships_left` (VA) is 0 after
`turn_over`, then (0x754..0x7D1) clears the screen, shows the score and ships and the end text
(`aysabtu`, or the HYPERSPACE! easter egg at score 255) and waits for a key (FX0A) to start over;
any step that ends there, or in a subroutine it called, ends the episode. Lives: VA.

Options from the archive: CHIP-8, tickrate 100 (the speed it is tuned for: the game waits on
the delay timer between ticks), Octo's default quirks, its colours. Start-up: 30 frames (the
title is drawn by frame 28 and waits at FX0A, 0x418), then key 5 held 2 frames, released by the
first env step, so the cave (`random`) is drawn from each episode's reset key. Episodes are cut
at 4,500 steps (5 minutes).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, register_value

SCORE, SHIPS_LEFT = 9, 10  # V9, VA
GAME_END = (0x754, 0x7D2)  # after `main`'s loop, through `aysabtu` and its FX0A

SPECS = (archive_spec(
    "spacejam",
    id="SpacejamArchive",
    rom_sha1="9f9a4affbf7afd70bb594fb321e16579318c0164",
    action_keys=(5, 8, 7, 9),
    score_fn=lambda state: register_value(state, SCORE),
    terminated_fn=lambda state: in_routine(state, *GAME_END),
    lives_fn=lambda state: register_value(state, SHIPS_LEFT),
    startup=((0, 30), (key_mask(5), 2)),
    max_episode_steps=4500,
    category="navigation",
    description="Fly the ship (keys 5/8 up and down, 7/9 left and right) through the cave; reward: "
                "the ROM's score (+1 per turn, +3 per obstacle passed, time bonuses); the game ends "
                "when the third ship crashes.",
),)
