"""Space Racer (Octojam 4, archive "spaceracer"): fly a ship up through a drifting starfield.

### Observation
The screen, uint8 (frames_per_step, 32, 64): a starfield (rows 0..27) scrolling left one pixel per
loop, the player's ship (3 rows, x 23) and the idle second ship (x 38) at the bottom, both scores
(3 digits, row 28) and the time bar on row 31, which shrinks from both ends.

### Actions
0: no-op, 1: key 4 (ship 1 up, `Key_Q`), 2: key 7 (ship 1 down, `Key_A`). The ROM reads no other
key during the race (keys D/E move ship 2, which is left idle).

### Reward
+1 per crossing: the change of `score1` (`:alias score1 v9`), which the ROM raises when ship 1
leaves the top (`ship1y` v8 wraps to 253) and sends it back to the bottom. A star hit costs
nothing but the climb: the ship is put back at the start. `score1` is not touched by the text,
number and flash routines of the results screen, so the reward never spikes.

### Termination
The time runs out: `timer_line` (v6), raised once per 64 scrolls, reaches 19, the main loop's exit
(the results screen at 0xA80 follows). It stays 19 through the results screen's flashes and
`v0 := key` wait.

Options from the archive: tickrate 20, no quirks. A race lasts about 2,750 steps (19 x 64 scrolls) at this speed;
episodes are cut at 4,500 steps. This is the two-player "Space Race": player 2 (keys D/E) is idle,
its ship stays at the bottom out of the stars, so the agent races the clock alone and the ROM's
WINNER!/TIE! verdict is ignored. Start-up: key 4 held and released on the title (`v0 := key`),
then on the two rules pages (the first ignores Q, the second quits the rules on Q), then 2 frames
to draw the starfield. The ROM draws no random numbers: the race is the same for every reset key
and depends only on the actions.
"""

from octax_core.env.games.archive._program import archive_spec
import jax.numpy as jnp

from octax_core.env.games.spec import Seats, key_mask

SCORE1 = 9  # `:alias score1 v9`
SCORE2 = 12  # `:alias score2 vc`
SHIP_Y = (8, 11)  # `:alias ship1y v8`, `:alias ship2y vb`
TIMER_LINE = 6  # `:alias timer_line v6`
TIME_UP = 19  # `if timer_line != 19 then again`: the main play loop's end

_PRESS_4 = ((key_mask(4), 3), (0, 120))

SPECS = (archive_spec(
    "spaceracer",
    id="SpaceRacer",
    rom_sha1="659cb966e976fcbcae76f6a8a07c65be4d18aae8",
    action_keys=(4, 7),
    score_fn=lambda state: state.V[SCORE1].astype("int32"),
    terminated_fn=lambda state: state.V[TIMER_LINE] == TIME_UP,
    startup=((0, 200),) + _PRESS_4 * 3,
    max_episode_steps=4500,
    seats=Seats(
        action_keys=((4, 7), (0xD, 0xE)),  # 4/Q up, 7/A down; D/R up, E/F down (the ROM's keys page)
        score_fn=lambda state: jnp.stack([state.V[SCORE1], state.V[SCORE2]]).astype(jnp.int32),
        names=("ship 1 (left)", "ship 2 (right)"),
    ),
    category="timing",
    description="Fly ship 1 up through a scrolling starfield with key 4 (key 7 down); reward +1 "
                "each time it reaches the top, a star hit sends it back to the start; the episode "
                "ends when the race's time bar runs out. Player 2's ship stays idle.",
),)
