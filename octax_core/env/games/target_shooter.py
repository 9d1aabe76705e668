"""Target Shooter (LLM-generated for the octax paper): move a crosshair onto targets, shoot.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the 8x8 crosshair and one 8x8 target at a time.

### Actions
0: no-op, 1: key 5 (up), 2: key 7 (left), 3: key 8 (down), 4: key 9 (right), 5: key 6 (shoot).
The crosshair moves 2 pixels per game loop (about one loop per step); a shot hits when the
crosshair's centre is within 6 pixels of the target's on both axes.

### Reward
Change of V2, +1 per hit.

### Termination
V3 (the game-over flag) becomes 1. Level 1 ends after 10 hits only, so a policy that never hits
runs to the step limit (octax's random policy never ended it). Levels 2 and 3 end once 10
targets have appeared, hit or timed out; the ROM checks this before the 10th can be shot, so
their best score is 9 (the paper's level-2 agents plateau at 9).

### Levels
Three Octo programs sharing the register map (V0, V1 crosshair; V4, V5 target; V2 score; V3
game over): 1 static targets; 2 targets vanish after 60 game loops (VC counts down); 3 targets
also move 0-3 pixels per loop and bounce (VD, VE velocity), vanishing after 80 loops; the ROM
erases and redraws a moving target across a frame end, so it is missing from ~1 frame in 4.

Category "reaction": one target at a time, find it and shoot, like the paper's other simple
shooting games; level 3's moving targets add some prediction. Quirks "chip8": written for
classic CHIP-8 with no quirk-sensitive opcode, so the profile only sets display-wait pacing;
it plays under "schip" too, a little faster. Timers: real 60 Hz; the game loop waits one frame
on the delay timer. Start-up: 2 frames, the crosshair drawn; the first target is placed during
the first step, from the reset key. Episodes are cut at 3,000 steps: a player that never hits
ends level 2 in about 550 steps and level 3 in about 1,450.
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

_LEVELS = (  # ROM file, SHA-1, title
    ("target_shooter1.ch8", "a57f388db66745a46a4587dc6800ff339f6bedea", "static targets"),
    ("target_shooter2.ch8", "50592422956e880b8c0db188a54fa769fa0c33fc", "targets time out"),
    ("target_shooter3.ch8", "c2320a6f71efa1d57fc650608015ba429ca337dd", "moving targets time out"),
)


def _spec(level: int, rom_file: str, sha1: str, kind: str) -> GameSpec:
    return GameSpec(
        id=f"TargetShooter{level}",
        title=f"Target Shooter, level {level} ({kind})",
        rom_file=rom_file,
        rom_sha1=sha1,
        action_keys=(5, 7, 8, 9, 6),
        score_fn=lambda state: state.V[2].astype(jnp.int32),
        terminated_fn=lambda state: state.V[3] == 1,
        startup=((0, 2),),
        quirks="chip8",
        max_episode_steps=3000,
        category="reaction",
        description="Move the crosshair (keys 5 up, 7 left, 8 down, 9 right) onto the target and "
                    "shoot (key 6); reward +1 per hit; the game ends after 10 hits (level 1) or "
                    "10 targets shown (levels 2-3).",
    )


SPECS = tuple(_spec(level, *row) for level, row in enumerate(_LEVELS, 1))
