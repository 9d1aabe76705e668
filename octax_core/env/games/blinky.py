"""Blinky (Hans Christian Egeberg, 1991): Pac-Man; eat the pills of a maze, avoid two ghosts.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the maze with its pills and four energy pills,
Blinky and the two ghosts (Packlett and Heward).

### Actions
0: no-op, 1: key 3 (down), 2: key 6 (up), 3: key 7 (left), 4: key 8 (right).

### Reward
Change of V6, the paper's score register: 1 per pill and 4 per energy pill of the current maze.

Where the ROM and the paper disagree: V6 is not the game's score. The ROM counts the current
maze's pills in V6, adds V6 to a 16-bit total at RAM 0x8C8 (high byte first) when the maze is
cleared or the game ends, and then zeroes V6; the ghost bonuses (50 for Packlett and 25 for
Heward caught while energized) and the 100 for a cleared maze go straight to the total. So
under the paper's rule catching a ghost earns nothing, and clearing a maze (247 in pills) is
one large negative reward: +1 for the last pill, then -247 four steps later as V6 drops back to
0 (measured). For the game's own score (total + V6) use instead, in a `dataclasses.replace` of
this spec, `score_fn=lambda s: s.memory[MEMORY_OFFSET + 0x8C8].astype(jnp.int32) * 256 +
s.memory[MEMORY_OFFSET + 0x8C9] + s.V[6].astype(jnp.int32)` (`octax_core.emulator.state.MEMORY_OFFSET`).

### Termination
V3 equals 255: the first time a ghost catches Blinky (the ROM's death pause at 0x8A8 counts
down with V3 = 255), as in the paper. Blinky has two lives; the episode ends at the first.

Quirks "schip": a SUPER-CHIP program (community database: superchip); it shifts VX in place
with 8XY6/8XYE where x != y, so under "chip8" (which shifts VY) the maze is drawn garbled.
Timers: real 60 Hz; the delay timer times an energy pill (255 frames), which frozen timers
would cut to the rest of one step. Start-up: 1,251 frames (octax: 13,800 instructions = 1,255),
while the ROM copies and draws the maze, up to its main loop. Episodes are cut at 9,000 steps
(10 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec


SPECS = (GameSpec(
    id="Blinky",
    title="Blinky",
    rom_file="Blinky [Hans Christian Egeberg, 1991].ch8",
    rom_sha1="d40abc54374e4343639f993e897e00904ddf85d9",
    action_keys=(3, 6, 7, 8),
    score_fn=lambda state: state.V[6].astype(jnp.int32),  # the paper's rule
    terminated_fn=lambda state: state.V[3] == 255,
    startup=((0, 1251),),
    quirks="schip",
    max_episode_steps=9000,
    category="planning",
    description="Steer Blinky (keys 3 down, 6 up, 7 left, 8 right) through the maze eating pills; "
                "an energy pill makes the ghosts edible for a while; the episode ends when a ghost "
                "catches Blinky.",
),)
