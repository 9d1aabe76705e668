"""Flight Runner (Octojam 1, archive "flightrunner"): fly a ship between two drifting walls.

The archive's original, not the octax suite's patched build (`FlightRunner`, which adds a score
register and a crash flag): this one keeps no score, so its reward is survival.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the ship on the left, a ceiling and a floor wall
scrolling left and drifting up and down at random.

### Actions
0: no-op, 1: key 5 (up), 2: key 8 (down), 3: key 7 (left), 4: key 9 (right); 1 pixel a loop.

### Reward
+1 for every step the ship is still flying after (`survival_reward`): the ROM keeps no score,
and staying between the walls is the whole game, so the return counts the steps survived.

### Termination
The ship touching a wall (`check-collision`, or three of the four wall sprites erasing the ship
in `update-walls`): `game-over` (0x2DF..0x306) draws "oops", waits 140 frames and calls `main`,
which starts over inside that call; any step that ends in `game-over` or below it ends the episode.

Options from the archive: CHIP-8, tickrate 15, Octo's default quirks, its colours. The source
reassembles with 4 bytes different (a comparison pseudo-op's temporary), every label in place.
A loop every 2 frames or more (`sync`). Start-up: none; every wall drift (`random 0b11`) is drawn
from each episode's reset key. Episodes are cut at 4,500 steps (5 minutes).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine

GAME_OVER = (0x2DF, 0x307)  # `game-over`, up to `check-collision`

SPECS = (archive_spec(
    "flightrunner",
    id="FlightRunnerArchive",
    rom_sha1="821751787374cc362f4c58759961f0aa7a2fd410",
    action_keys=(5, 8, 7, 9),
    score_fn=lambda state: 0,
    survival_reward=1.0,
    terminated_fn=lambda state: in_routine(state, *GAME_OVER),
    max_episode_steps=4500,
    category="navigation",
    description="Fly the ship (keys 5/8 up and down, 7/9 left and right) between the drifting walls; "
                "reward +1 per step survived (the ROM keeps no score); the game ends when the ship "
                "touches a wall.",
),)
