"""Squash (David Winter, 1997): keep a ball in play against three walls with a paddle.

### Observation
The screen, uint8 (frames_per_step, 32, 64): walls on top, bottom and right, the paddle on the
left, the ball, and the balls left on the right.

### Actions
0: no-op, 1: key 1 (paddle up), 2: key 4 (paddle down).

### Reward
Change of V11, the balls left (5 at the start): -1 per ball missed, as in the paper.

### Termination
V11 reaches 0. After a miss the ROM waits (FX0A) for a key to be pressed and released, and only
then takes the ball off V11 and serves again; a policy that never changes its action stalls
there until truncation.

Quirks "chip8": an original CHIP-8 program (community database: originalChip8, modernChip8);
the quirks that differ do not change its logic (no shift or BNNN; VF after 8XY1 and I after
FX65 are never read), so the profile only sets the VIP's display-wait pacing. Timers: real 60
Hz; the game loop waits one frame of delay timer per ball move. Start-up: 26 frames (octax: 100
instructions = 10), until the court and the balls left are drawn. The paddle's first row is
the ROM's only random draw and comes before V11 is set, so every episode starts the same (use
`noop_max` to vary the start). Episodes are cut at 4,500 steps (5 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

SPECS = (GameSpec(
    id="Squash",
    title="Squash",
    rom_file="Squash [David Winter].ch8",
    rom_sha1="a58ec7cc63707f9e7274026de27c15ec1d9945bd",
    action_keys=(1, 4),
    score_fn=lambda state: state.V[11].astype(jnp.int32),
    terminated_fn=lambda state: state.V[11] == 0,
    lives_fn=lambda state: state.V[11].astype(jnp.int32),
    startup=((0, 26),),
    quirks="chip8",
    max_episode_steps=4500,
    category="timing",
    description="Move the paddle (keys 1 up, 4 down) to keep the ball in the court; reward -1 per "
                "ball missed; the game ends when the 5 balls are gone.",
),)
