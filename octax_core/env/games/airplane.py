"""Airplane: a plane crosses the top of the screen and drops bombs through traffic below it.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the player's plane on top, 1 to 3 planes crossing
below it, the ground line, the level digit and a 4-segment bar at the bottom.

### Actions
0: no-op, 1: key 8 (drop a bomb; one falls at a time).

### Reward
The paper's: change of -(VB + VC). VB (4 at the start, the bar) drops by one when a bomb hits a
plane; VC (the level digit, 1..5) rises by one when a bomb reaches the ground. Reading the ROM,
VB looks like lives (a hit restarts the level) and VC like the level reached (more and faster
planes), so this reward favours hits; kept as published. VC wraps from 5 to 1 within one frame,
so finishing level 5 pays +4.

### Termination
VB == 0 (the ROM halts at pc 0x308) or VC == 6 (the paper's; under "chip8" at 11 instructions
per frame VC is 6 only inside one frame, never at a step boundary, so the game ends on VB == 0).

Quirks "chip8": an original CHIP-8 program (community database: originalChip8) using no
quirk-sensitive opcode; the profile only sets the VIP's display-wait pacing. Timers: real 60 Hz:
the delay timer only times the 48-frame pause before each level.
Start-up: 60 frames (octax: 600 instructions = 55), through the first pause into play. Episodes
are cut at 4,500 steps (5 minutes); random play ends in about 750.
"""


from octax_core.env.games.spec import GameSpec, register_value


SPECS = (GameSpec(
    id="Airplane",
    title="Airplane",
    rom_file="Airplane.ch8",
    rom_sha1="fca71182a8838b686573e69b22aff945d79fe1d0",
    action_keys=(8,),
    score_fn=lambda state: -(register_value(state, 11) + register_value(state, 12)),
    terminated_fn=lambda state: (state.V[11] == 0) | (state.V[12] == 6),
    lives_fn=lambda state: register_value(state, 11),
    startup=((0, 60),),
    quirks="chip8",
    max_episode_steps=4500,
    category="reaction",
    description="Drop bombs (key 8) from a plane crossing the top of the screen; reward is the change "
                "of -(VB + VC): +1 when a bomb hits a plane (VB drops), -1 when one reaches the ground "
                "(VC, the level, rises); the game ends when VB reaches 0.",
),)
