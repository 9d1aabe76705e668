"""Missile Command (David Winter, 1996): a launcher sweeps the bottom; shoot the 8 targets on top.

### Observation
The screen, uint8 (frames_per_step, 32, 64): 8 targets in a row on top, the launcher at the bottom.

### Actions
0: no-op, 1: key 8 (fire). The launcher moves by itself and speeds up after every shot.

### Reward
Change of V7, the points: 5 per target hit.

### Termination
V6 (missiles left, 10 at the start; every shot spends one) reaches 0, or V5 (targets left)
reaches 0. The paper ends on V6 only, but a game that hits all 8 targets with missiles to spare
halts (pc 0x2AB) with V6 > 0 and would never end.

Quirks "chip8": an original CHIP-8 program (community database: originalChip8); it uses no
quirk-sensitive opcode, so the profile only sets the VIP's display-wait pacing. Timers: real
60 Hz (the launcher waits VC frames per move, so the delay timer sets the game's speed).
Start-up: 10 frames (octax: 50 instructions = 5), until the 8 targets are drawn (one sprite per
frame under display wait). Episodes are cut at 2,700 steps (3 minutes); ten shots take about 150.
"""


from octax_core.env.games.spec import GameSpec, register_value


SPECS = (GameSpec(
    id="Missile",
    title="Missile Command",
    rom_file="Missile [David Winter].ch8",
    rom_sha1="0d0cc129dad3c45ba672f85fec71a668232212cc",
    action_keys=(8,),
    score_fn=lambda state: register_value(state, 7),
    terminated_fn=lambda state: (state.V[6] == 0) | (state.V[5] == 0),
    startup=((0, 10),),
    quirks="chip8",
    max_episode_steps=2700,
    category="resources",
    description="Fire (key 8) from a moving launcher at 8 targets: 5 points a hit, 10 missiles; "
                "reward is the change of V7; the game ends when the missiles or the targets run out.",
),)
