"""Black Rainbow (Octojam 3, archive "blackrainbow"): cross a random world of rooms to the
Motherlode, against the clock.

### Observation
The screen, uint8 (frames_per_step, 64, 128): one room of 16x8 tiles of 8x8 pixels (SUPER-CHIP
hires): walls with doors to the next rooms, decor, gems, the player (a 5x6 figure, 1 pixel a
move) and the room's mobs (slicers, lungers, sentionauts, wisps, plants, bombs, a ghost that
mirrors the player); in the Motherlode's room a large eye whose pupil follows the player.

### Actions
0: no-op, 1: key 5 (Octo's W: up), 2: key 8 (S: down), 3: key 7 (A: left), 4: key 9 (D: right);
keys are read every loop (1 frame), several at once in the ROM but one per action here. (Key 0,
Octo's X, which pauses and shows the time, is not offered.)

### Reward
-1 per time unit on the ROM's clock and +2 per gem taken. It is minus the change of the time the ROM keeps and shows at the end, `timer-data` (0xA2F, units, and
0xA30, hundreds): it counts up once every 64 loops (`global-timer`, `tick` v7 up to `tick-max`),
and each gem taken (`take-gem`) sets it back by `gem-time`, 2, never below 0. So -1 per time unit
and +2 per gem (less at a time under 2); the return is minus the final time, the game's own score
(lower is better). A mob's touch (`scramble`) is no death: the screen fills with noise for 30
frames and the player goes back to where it entered the room, losing time.

### Termination
Touching the Motherlode's pupil (world room (3, 3), the `0xFF` contents `build-world` gives it):
`motherlode` clears the screen, closes the eye and shows the time (0xBE6..0xC0D, with
`motherlode-anim`, `timer-wait` and `show-score`, which waits for a key before
`reset-everything` builds a new world); the pc there or in a routine called from there is the end.

Options from the archive: SUPER-CHIP, tickrate 20, Octo's default quirks, its colours. A game loop
is one frame (`delay` 1) where the ROM keeps up, as in the empty start room (a time unit about
every 16 steps); with mobs to run it takes 4 or 5 frames (and the player, 1 pixel a loop, slows
down with it). Start-up: 40
frames (the title and its tunnel drawn), key 9 held 45 frames (the title's player walks right to
x 122, as the title asks); the start-up ends before `reset-everything` runs `build-world`, so
every world (its 25 rooms' layouts, doors and mobs, `random`) is drawn from each episode's reset
key. The start room (0, 0) is empty; the Motherlode is two rooms left and two up (the world
wraps). Episodes are cut at 4,500 steps (5 minutes).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, ram_value

TIMER_DATA = 0xA2F  # `timer-data`: units (0..99), then `timer-data-high`: hundreds
THE_END = (0xBE6, 0xC0E)  # `motherlode` after the pupil's touch, up to its `show-score` call


def _minus_time(state):
    return -(ram_value(state, TIMER_DATA + 1) * 100 + ram_value(state, TIMER_DATA))


SPECS = (archive_spec(
    "blackrainbow",
    id="BlackRainbow",
    rom_sha1="e6af47843f0ecc3302027a3756dd7b389a15e437",
    action_keys=(5, 8, 7, 9),
    score_fn=_minus_time,
    terminated_fn=lambda state: in_routine(state, *THE_END),
    startup=((0, 40), (key_mask(9), 45)),
    max_episode_steps=4500,
    category="navigation",
    description="Walk the player (keys 5/8/7/9: up, down, left, right) through a random world of "
                "rooms, past their mobs, to the Motherlode's eye; reward -1 per time unit (every "
                "64 game loops) and +2 per gem taken, the ROM's own clock; the game ends when the "
                "player touches the eye's pupil.",
),)
