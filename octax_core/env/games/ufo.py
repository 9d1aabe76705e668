"""UFO (a 1977 VIP cassette game, posted by Lutz V in 1992): shoot UFOs from a fixed launcher.

### Observation
The screen, uint8 (frames_per_step, 32, 64): a large and a small UFO crossing the sky, the
launcher at the bottom centre, score (left) and missiles left (right) along the bottom.

### Actions
0: no-op, 1: key 4 (fire up-left), 2: key 5 (fire straight up), 3: key 6 (fire up-right).
One missile flies at a time.

### Reward
Change of V7, the points: 5 for the large UFO, 15 for the small one.

### Termination
V8 (missiles left, 15 at the start, one spent per missile once it has hit or left the screen)
reaches 0.

Quirks "chip8": an original COSMAC VIP program (community database: originalChip8) using no
quirk-sensitive opcode; the profile only sets the VIP's display-wait pacing. Timers: real 60 Hz;
the game uses only the sound timer, so freezing them would change nothing.
Start-up: 10 frames (octax: 50 instructions = 5), until score and missiles are drawn. Episodes
are cut at 2,700 steps (3 minutes); 15 missiles take about 650.
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

SPECS = (GameSpec(
    id="UFO",
    title="UFO",
    rom_file="UFO [Lutz V, 1992].ch8",
    rom_sha1="bdb92475acfe11bc7814a2f5eade13fcd09b756a",
    action_keys=(4, 5, 6),
    score_fn=lambda state: state.V[7].astype(jnp.int32),
    terminated_fn=lambda state: state.V[8] == 0,
    startup=((0, 10),),
    quirks="chip8",
    max_episode_steps=2700,
    category="resources",
    description="Fire 15 missiles up-left, up or up-right (keys 4, 5, 6) at two UFOs: 5 points for the "
                "large one, 15 for the small one; reward is the change of V7; the game ends when the "
                "missiles are spent.",
),)
