"""Rocket (Joseph Weisbecker, BYTE magazine, December 1978): launch rockets at a passing UFO.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the UFO drifting right along the top, a rocket at a
random spot on the bottom edge, the one-digit score at the lower right.

### Actions
0: no-op, 1: key F (launch the rocket standing on the pad).

### Reward
Change of V1, the hits (one point per rocket that hits the UFO).

### Termination
The game halts after the 9th rocket (pc parked at 0x214, V2 == 9). The paper ends on V2 == 9
alone, but V2 counts rockets *placed*: it reaches 9 when the 9th rocket appears on the pad, so
that rocket could never be flown and the best score would be 8, not 9.

Quirks "chip8": an original COSMAC VIP program (community database: originalChip8) using no
quirk-sensitive opcode; the profile only sets the VIP's display-wait pacing. Timers: real 60 Hz
(a flying rocket climbs one row every 3 frames of the delay timer).
Start-up: 3 frames, until the first rocket and the score are drawn (octax uses none). Episodes
are cut at 2,700 steps (3 minutes); nine rockets take about 300.
"""

import jax.numpy as jnp

from octax_core.games.spec import GameSpec

_HALT = 0x214  # `JP 214`: the end-of-game loop


SPECS = (GameSpec(
    id="Rocket",
    title="Rocket",
    rom_file="Rocket [Joseph Weisbecker, 1978].ch8",
    rom_sha1="3d1d029d6e31206d245c0ba881c0d1f003953bad",
    action_keys=(15,),
    score_fn=lambda state: state.V[1].astype(jnp.int32),
    terminated_fn=lambda state: (state.V[2] == 9) & (state.pc == _HALT),
    startup=((0, 3),),
    quirks="chip8",
    max_episode_steps=2700,
    category="resources",
    description="Launch (key F) 9 rockets one at a time at a UFO crossing the top of the screen; "
                "reward is the change of V1 (hits); the game ends after the 9th rocket.",
),)
