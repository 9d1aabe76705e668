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
The game-over halt (pc 0x394), reached once V6 (bombs left, 25 at the start; running into the
target costs 5) is 0 and no bomb is flying. The paper ends on V6 == 0 alone, which fires as
the last bomb leaves the tank, so that bomb's hit could never be rewarded.

Quirks "chip8": an original CHIP-8 program (community database: originalChip8); it sets I before
every FX55/FX65, so the profile only sets the VIP's display-wait pacing. Timers: real 60 Hz: the
delay timer is used only for the 64-frame pause before each round (octax zeroes it, skipping the
pause); the pause is part of the game and costs 16 steps.
Start-up: 80 frames (octax: 100 instructions, with the pause zeroed), through the first round's
pause into play. Episodes are cut at 4,500 steps (5 minutes); 25 bombs take 700 to 1,350.
"""

import jax.numpy as jnp

from octax_core.games.spec import GameSpec

_GAME_OVER = 0x394  # `JP 394`: the end-of-game loop


SPECS = (GameSpec(
    id="Tank",
    title="Tank Battle",
    rom_file="Tank.ch8",
    rom_sha1="18b9d15f4c159e1f0ed58c2d8ec1d89325d3a3b6",
    action_keys=(2, 4, 5, 6, 8),
    score_fn=lambda state: state.V[14].astype(jnp.int32),
    terminated_fn=lambda state: state.pc == _GAME_OVER,
    startup=((0, 80),),
    quirks="chip8",
    max_episode_steps=4500,
    category="resources",
    description="Drive a tank (keys 2/4/6/8, 2 and 8 swapped) and fire bombs (key 5) at a roaming "
                "target: 10 points a hit, 25 bombs, 5 lost for running into the target; reward is the "
                "change of VE; the game ends when the bombs are spent.",
),)
