"""Tank Battle: drive a tank and bomb a target that roams the screen.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the tank and the target; score and bombs left show
during the pause before each round.

### Actions
0: no-op, 1: key 2 (drive down: the original keypad's 2 and 8 are swapped), 2: key 4 (left),
3: key 5 (fire a bomb the way the tank faces), 4: key 6 (right), 5: key 8 (up).

### Reward
Change of VE, the points: 10 per bomb that hits the target.

### Termination
V6 (bombs left, 25 at the start; running into the target costs 5) equals 0 (the paper's rule).

Where the ROM and the paper disagree: V6 drops to 0 as the last bomb leaves the tank (or as
the tank runs into the target with 5 or fewer left: the ROM clamps V6 at 0), so the episode
usually ends with the last bomb still flying, and its hit is never rewarded. The ROM lets the
last bomb land and then halts in a jump-to-self at pc 0x394; to wait for it use instead
`terminated_fn=lambda s: s.pc == 0x394` in a `dataclasses.replace` of this spec.

Quirks "chip8": an original CHIP-8 program (community database: originalChip8); it sets I before
every FX55/FX65, so the profile only sets the VIP's display-wait pacing. Timers: real 60 Hz: the
delay timer is used only for the 64-frame pause before each round (octax zeroes it, skipping the
pause); the pause is part of the game and costs 16 steps.
Start-up: 80 frames (octax: 100 instructions, with the pause zeroed), through the first round's
pause into play. Episodes are cut at 4,500 steps (5 minutes); one ends after 595-974 steps
under random play and 1,278 with key 5 held (measured; the ROM's halt came 4-76 steps later).
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec


SPECS = (GameSpec(
    id="Tank",
    title="Tank Battle",
    rom_file="Tank.ch8",
    rom_sha1="18b9d15f4c159e1f0ed58c2d8ec1d89325d3a3b6",
    action_keys=(2, 4, 5, 6, 8),
    score_fn=lambda state: state.V[14].astype(jnp.int32),
    terminated_fn=lambda state: state.V[6] == 0,  # the paper's rule
    startup=((0, 80),),
    quirks="chip8",
    max_episode_steps=4500,
    category="resources",
    description="Drive a tank (keys 2/4/6/8, 2 and 8 swapped) and fire bombs (key 5) at a roaming "
                "target: 10 points a hit, 25 bombs, 5 lost for running into the target; reward is the "
                "change of VE; the episode ends when V6, the bombs left, reaches 0 (the paper's rule).",
),)
