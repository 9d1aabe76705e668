"""Danm8ku (Octojam 2, archive "danm8ku"): a bullet hell; survive 8 waves of bullet patterns.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the player (a 3x3 ship), the bullets (2x2, in many
directions and speeds) and on the right a column of marks, one per wave survived.

### Actions
0: no-op, 1: key 5 (up), 2: key 8 (down), 3: key 7 (left), 4: key 9 (right): half a pixel a loop
(`player_position` keeps doubled coordinates).

### Reward
+1 per pattern phase survived: the change of `pattern_state` (RAM 0x2AD), which `next_pattern`
increments every 255 ticks; a wave is two phases (bullets, then a pause marked on the right).

### Termination
A bullet hitting the player (VF from the player's sprite): `show_you_lose_screen` (0x396..0x3AB)
shows OUCH and waits for two keys (FX0A) before the title; or the last wave survived:
`show_you_win_screen` (0x322..0x395, with `draw_win_data`) animates YES forever. A step that ends
in either ends the episode.

Options from the archive: CHIP-8, tickrate 1000 (the bullet engine is slow: "act_bullets takes a
long time"), Octo's default quirks, its colours; one tick per frame (`sync`). Start-up: 3 frames
(the title drawn and animating), key 5 held 1 frame: the title returns as soon as one of keys 5,
7, 8, 9 is down, so every bullet pattern (`random`) is drawn from each episode's reset key.
Episodes are cut at 4,500 steps (5 minutes; 8 waves take about 16 x 255 ticks, 68 s).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, ram_value

PATTERN_STATE = 0x2AD
END_SCREENS = (0x322, 0x3AC)  # `show_you_win_screen`, `draw_win_data`, `show_you_lose_screen`

SPECS = (archive_spec(
    "danm8ku",
    id="Danm8ku",
    rom_sha1="ff6b8ac59bf281cd4b5ab6e161600b00f85a0265",
    action_keys=(5, 8, 7, 9),
    score_fn=lambda state: ram_value(state, PATTERN_STATE),
    terminated_fn=lambda state: in_routine(state, *END_SCREENS),
    startup=((0, 3), (key_mask(5), 1)),
    max_episode_steps=4500,
    category="reaction",
    description="Dodge the bullet patterns (keys 5/8 up and down, 7/9 left and right); reward +1 per "
                "pattern phase survived (two per wave); the game ends at the first hit or after the "
                "eighth wave.",
),)
