"""Rocket (Joseph Weisbecker, BYTE magazine, December 1978): launch rockets at a passing UFO.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the UFO drifting right along the top, a rocket at a
random spot on the bottom edge, the one-digit score at the lower right.

### Actions
0: no-op, 1: key F (launch the rocket standing on the pad).

### Reward
Change of V1, the hits (one point per rocket that hits the UFO).

### Termination
V2 equals 9 (the paper's rule). V2 counts the rockets placed on the pad, 1 at the start.

Where the ROM and the paper disagree: the paper calls V2 "rocket launched", but it reaches 9
when the 9th rocket appears on the pad, before it is launched, so the episode ends with that
rocket unflown and the best score is 8 of the ROM's 9. The ROM itself plays the 9th rocket and
then halts in a jump-to-self at pc 0x214; to play it use instead
`terminated_fn=lambda s: (s.V[2] == 9) & (s.pc == 0x214)` in a `dataclasses.replace` of this spec.

Quirks "chip8": an original COSMAC VIP program (community database: originalChip8) using no
quirk-sensitive opcode; the profile only sets the VIP's display-wait pacing. Timers: real 60 Hz
(a flying rocket climbs one row every 3 frames of the delay timer).
Start-up: 3 frames, until the first rocket and the score are drawn (octax uses none). Episodes
are cut at 2,700 steps (3 minutes). One ends after 249-281 steps with key F held, 238-305 under
random play (measured; with key F held the ROM's halt came 24-40 steps later); with no launch
the first rocket waits on the pad and the episode runs to the cut.
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec


SPECS = (GameSpec(
    id="Rocket",
    title="Rocket",
    rom_file="Rocket [Joseph Weisbecker, 1978].ch8",
    rom_sha1="3d1d029d6e31206d245c0ba881c0d1f003953bad",
    action_keys=(15,),
    score_fn=lambda state: state.V[1].astype(jnp.int32),
    terminated_fn=lambda state: state.V[2] == 9,  # the paper's rule
    startup=((0, 3),),
    quirks="chip8",
    max_episode_steps=2700,
    category="resources",
    description="Launch (key F) 9 rockets one at a time at a UFO crossing the top of the screen; "
                "reward is the change of V1 (hits); the episode ends as the 9th rocket appears on the "
                "pad (V2 == 9, the paper's rule), so 8 rockets fly.",
),)
