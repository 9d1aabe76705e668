"""Snek (Octojam 8, archive "snek"): Snake (or rather a light cycle) in 65 bytes of CHIP-8.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the trail the snake's head leaves; nothing is ever
erased, so the trail only grows, and the screen wraps at the edges.

### Actions
0: no-op, 1: key 9 (Octo's D: right), 2: key 5 (W: up), 3: key 7 (A: left), 4: key 8 (S: down);
the head keeps going the way it was last sent.

### Reward
+1 for every step the snake survives after (`survival_reward`): the 65-byte program keeps no
score, and the trail's length is the time survived.

### Termination
The head running into the trail (VF after drawing it): the loop ends at FX0A (0x234), which
waits for a key and restarts; a step that ends there ends the episode.

Options from the archive: CHIP-8, tickrate 1000, Octo's default quirks, its colours. A move every
frame (the delay timer, `registers`: interframe delay 1). Start-up: none (the game is the same in
every episode: it draws no random numbers; only the policy varies it). The ROM spends nearly all
of its 1,000 instructions a frame waiting on the delay timer. Episodes are cut at 4,500 steps.
"""

from octax_core.env.games.archive._program import archive_spec

WAIT_KEY = 0x234  # the FX0A after the game loop

SPECS = (archive_spec(
    "snek",
    id="Snek",
    rom_sha1="bb5740042385cae10724b051208bb95e5341f56d",
    action_keys=(9, 5, 7, 8),
    score_fn=lambda state: 0,
    survival_reward=1.0,
    terminated_fn=lambda state: state.pc == WAIT_KEY,
    max_episode_steps=4500,
    category="planning",
    description="Steer the growing trail (keys 9 right, 5 up, 7 left, 8 down) without running into "
                "it; reward +1 per step survived (the 65-byte ROM keeps no score); the game ends at "
                "the first collision.",
),)
