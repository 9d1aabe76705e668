"""Super Octogon (Octojam 8, archive "octogon"): Super Hexagon on an octagon; dodge the closing walls.

### Observation
The screen, uint8 (frames_per_step, 64, 128), SUPER-CHIP lores (each pixel a 2x2 block): an
octagon whose eight segments shift inward in patterns, and the player, a pixel running round a
small octagon in the middle.

### Actions
0: no-op, 1: key 7 (Octo's A: counter-clockwise), 2: key 9 (D: clockwise); two of 64 positions
per move.

### Reward
+1 per wave survived: the change of `waves` (RAM 0x202), which the board's animation counts up.

### Termination
A wall touching the player (VF from its pixel): `move-player` buzzes, waits, shows the waves
survived and waits for a key (FX0A) before `reset` (0xF8F..0xFBE); a step that ends there, or in
the `wait` it calls, ends the episode.

Options from the archive: SUPER-CHIP, tickrate 200, Octo's default quirks, its colours; a move
every 4 frames (`wait`). Start-up: 5 frames (the title animating), key 7 held 2 frames: the
title loop leaves when A is down, and `reset` starts the game, so the walls' patterns are drawn
from each episode's reset key. Episodes are cut at 4,500 steps (5 minutes).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, ram_value

WAVES = 0x202
CRASH = (0xF8F, 0xFBF)  # `move-player`'s collision branch, through its FX0A

SPECS = (archive_spec(
    "octogon",
    id="SuperOctogon",
    rom_sha1="bb1e786cb921f51d0540cca9a216c0b72bceb443",
    action_keys=(7, 9),
    score_fn=lambda state: ram_value(state, WAVES),
    terminated_fn=lambda state: in_routine(state, *CRASH),
    startup=((0, 5), (key_mask(7), 2)),
    max_episode_steps=4500,
    category="reaction",
    description="Run round the octagon (keys 7 and 9) through the gaps in the closing walls; reward "
                "+1 per wave survived; the game ends when a wall hits the player.",
),)
