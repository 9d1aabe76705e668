"""Sw8 Copter (archive "sweetcopter"): Swing Copters for SUPER-CHIP; fly up between the girders.

### Observation
The screen, uint8 (frames_per_step, 64, 128), hires: the copter (a face under its blades) and
the girders it must pass; the screen scrolls as it climbs.

### Actions
0: no-op, 1: key 6 (`BUTTON`, Octo's E): reverse the copter's sideways drift (once per press;
the key must be released before it counts again, `wait-release`).

### Reward
+1 per 64 pixels climbed: the change of `score` (V7, `:alias score v7`), which `move-up` adds to
whenever the height wraps a multiple of 64.

### Termination
A collision (`collide`, VF of the copter's sprites): the ROM jumps to `game-over` (0x286), shakes
the screen for 16 frames, then `show-score` shows the score and waits for key 6, after which it
falls into `main` and starts over; any step that ends inside `game-over` or `show-score` (0x286
..0x2C5, or a subroutine they call) ends the episode, and the 16-frame shake (4 steps) makes sure
one does before the score is reset.

Options from the archive: SUPER-CHIP, tickrate 100 ("runs best at 100 cycles/frame"), Octo's
default quirks, its colours. A move every 2 frames (`sync`). Start-up: 5 frames (girders drawn,
`wait-key` waiting for key 6, which the first step holding it answers); the climb (`random 1`:
one or two pixels a move) is drawn from each episode's reset key. Episodes are cut at 4,500 steps.
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, register_value

SCORE = 7  # V7
GAME_OVER = (0x286, 0x2C6)  # `game-over` and `show-score`, up to `main`

SPECS = (archive_spec(
    "sweetcopter",
    id="Sw8Copter",
    rom_sha1="531c44e8204d8ab8c078bad36e34067baddfccdb",
    action_keys=(6,),
    score_fn=lambda state: register_value(state, SCORE),
    terminated_fn=lambda state: in_routine(state, *GAME_OVER),
    startup=((0, 5),),
    max_episode_steps=4500,
    category="timing",
    description="Tap key 6 to reverse the copter's drift as it climbs between girders; reward +1 "
                "per 64 pixels climbed; the game ends at the first collision.",
),)
