"""SuperWorm V4 (RB, Revival Studios, 2007): Snake; steer a growing worm to the food.

### Observation
The screen, uint8 (frames_per_step, 32, 64): a walled field, the worm, one food item and the
score on the right.

### Actions
0: no-op (keep going), 1: key 2 (up), 2: key 8 (down), 3: key 4 (left), 4: key 6 (right).
Turning back into the worm's own body is a collision.

### Reward
Change of V5, the food eaten: +1 per item.

### Termination
V7 equals 255: in this ROM, patched by the octax authors (source beside it: `Worm V4
[RB-Revival Studios, 2007].8o`), V7 is set to 255 when the worm hits a wall or itself, then the
game loops forever. V7 holds 124 until the field is drawn and 0 during play.

Quirks "chip8": the unpatched ROM is an original CHIP-8 program (community database:
originalChip8; the patched bytes are not listed); the only quirk-dependent code is an FX55
loop clearing the worm's position tables, which clears them under both profiles. Timers: real
60 Hz; each move ends with a 6-frame delay-timer wait that reads the keys. Start-up: 237 frames
(octax: 1,600 instructions = 146), until the walls are drawn; the first food position is drawn
from the reset key. Episodes are cut at 4,500 steps (5 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

SPECS = (GameSpec(
    id="Worm",
    title="SuperWorm V4",
    rom_file="Worm V4 [RB-Revival Studios, 2007].ch8",
    rom_sha1="54b2b475e8522421be83b643d50f48a1ccaab74f",
    action_keys=(2, 8, 4, 6),
    score_fn=lambda state: state.V[5].astype(jnp.int32),
    terminated_fn=lambda state: state.V[7] == 255,
    startup=((0, 237),),
    quirks="chip8",
    max_episode_steps=4500,
    category="planning",
    description="Steer the worm (keys 2 up, 8 down, 4 left, 6 right) to the food; reward +1 per "
                "item eaten; the game ends when the worm hits a wall or itself.",
),)
