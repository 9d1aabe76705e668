"""Submarine (Carmelo Cortez, 1978): drop depth charges from a ship on submarines passing below.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the ship on top, two submarines at different depths
crossing below, score (left) and charges left (right) along the top.

### Actions
0: no-op, 1: key 5 (drop a depth charge; one is in the water at a time).

### Reward
Change of V7, the points: 5 for the large submarine, 10 for the small one (the original text
says 15; the ROM adds 10).

### Termination
V8 (depth charges left, 25 at the start, one spent per charge once it has sunk or hit) reaches 0.

Quirks "chip8": an original COSMAC VIP program (community database: originalChip8) using no
quirk-sensitive opcode; the profile only sets the VIP's display-wait pacing. Timers: real 60 Hz;
the game uses only the sound timer, so freezing them would change nothing.
Start-up: 10 frames (octax: 100 instructions), until score and charges are drawn. Episodes are
cut at 2,700 steps (3 minutes); 25 charges take about 650.
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

SPECS = (GameSpec(
    id="Submarine",
    title="Submarine",
    rom_file="Submarine [Carmelo Cortez, 1978].ch8",
    rom_sha1="89aadf7c28bcd1c11e71ad9bd6eeaf0e7be474f3",
    action_keys=(5,),
    score_fn=lambda state: state.V[7].astype(jnp.int32),
    terminated_fn=lambda state: state.V[8] == 0,
    startup=((0, 10),),
    quirks="chip8",
    max_episode_steps=2700,
    category="resources",
    description="Drop depth charges (key 5) on two submarines: 5 points for the large one, 10 for the "
                "small one; reward is the change of V7; the game ends when the 25 charges are spent.",
),)
