"""Deep8 (John Earnest, 2014): a boat on the surface bombs squid rising from the deep.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the boat above the waves, the three-digit score at
the top right, squid climbing from the bottom.

### Actions
0: no-op, 1: key 7 (move left), 2: key 8 (hold to sink a bomb, release to detonate it),
3: key 9 (move right).

### Reward
Change of V9, the squid destroyed.

### Termination
VB (the boat's row, 1 while afloat) leaves 1: a squid has reached the boat, which sinks and the
program halts.

Quirks "chip8": written in Octo for the original CHIP-8 (community database: originalChip8); it
sets I before every FX55/FX65 and reads no flag after a logic op, so the profile only sets the
VIP's display-wait pacing. Timers: real 60 Hz; the game uses no timer at all (its speed is the
instruction rate), so freezing them would change nothing.
Start-up: key 0 held 20 frames, then 16 frames with no key: the title screen waits (FX0A) for a
key press and release (octax holds key 0 for 150 instructions = 14 frames; 20 leaves a margin
at lower instruction rates). Episodes are cut at 4,500 steps (5 minutes); with no key pressed
the first squid sinks the boat in under 50 steps.
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec, key_mask

SPECS = (GameSpec(
    id="Deep8",
    title="Deep8",
    rom_file="Deep8 (by John Earnest)(2014).ch8",
    rom_sha1="b41cc0b5b2faabafd532d705b804abb3e8f97baf",
    action_keys=(7, 8, 9),
    score_fn=lambda state: state.V[9].astype(jnp.int32),
    terminated_fn=lambda state: state.V[11] != 1,
    startup=((key_mask(0), 20), (0, 16)),
    quirks="chip8",
    max_episode_steps=4500,
    category="reaction",
    description="Steer a boat (keys 7, 9) and drop bombs (hold key 8, release to detonate) on squid "
                "rising towards it; reward is the change of V9 (squid destroyed); the game ends when a "
                "squid reaches the boat.",
),)
