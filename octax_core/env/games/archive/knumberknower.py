"""Knumber Knower (Octojam 10, archive "knumberknower"): compare two numbers in a cursed font.

### Observation
The screen, uint8 (frames_per_step, 32, 64): two numbers (`num-a` on top, `num-b` below) drawn
in a font whose digits all have different widths, a band with the three answer icons (V, =, ^)
between them, and the time dot moving right to left along the bottom row.

### Actions
0: no-op, 1: key 7 (A: top number greater), 2: key 5 (W: equal), 3: key 9 (D: top number
smaller). These are the three keys `game-screen` reads (`OCTO_KEY_A/W/D`); the answer counts when
the key is released (`loop if KEYREG key then again`).

### Reward
+1 per correct answer: the change of the decimal score the ROM keeps at `score` (0xCE8, one digit
a byte in bytes 1..6, raised by `score-inc` after each right answer). The registers are reused by
every routine, so the score is read from RAM; it is only cleared by `score-reset` after the score
screen and the title, well after the episode has ended.

### Termination
A wrong answer (`icon-validate` sets `gameover` v9) or the time dot reaching the left edge
(`time` v7 = 0) both end in `game-ended` (0x295..0x2A6), which buzzes for 60 frames and then
waits for a key: pc inside it. (`gameover` itself is not used: `nums-compare` borrows v9.)

Options from the archive: tickrate 15, VIP quirks as Octo's options give them (vblank: one sprite
per frame, clipping, logic), real timers: the time dot moves 2 pixels every 3 frames, about 23
steps per question. The numbers start with 2 digits and gain one each 10 points, up to 6.
Start-up: 90 frames of title animation, W held 100 frames (title-finish), released 30 frames
(the controls page is drawn), then W held 3 frames: `controls-finish` waits for W's release, so
the first question's digits (`num-pick`, CXNN) are drawn from each episode's reset key.
Episodes are cut at 4,500 steps (5 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import key_mask, ram_value

SCORE = 0xCE8  # `score`: 7 bytes, digits in bytes 1..6 (most significant first)
GAME_ENDED = (0x295, 0x2A7)  # `game-ended` up to `game-screen`
W = 5  # OCTO_KEY_W


def _score(state):
    total = jnp.int32(0)
    for offset in range(1, 7):
        total = total * 10 + ram_value(state, SCORE + offset, 1).astype(jnp.int32)
    return total


SPECS = (archive_spec(
    "knumberknower",
    id="KnumberKnower",
    rom_sha1="95f4af2d410c1acfd1b0657721a870a57c55b49b",
    action_keys=(7, 5, 9),
    score_fn=_score,
    terminated_fn=lambda state: (state.pc >= GAME_ENDED[0]) & (state.pc < GAME_ENDED[1]),
    startup=((0, 90), (key_mask(W), 100), (0, 30), (key_mask(W), 3)),
    max_episode_steps=4500,
    category="reaction",
    description="Two numbers are shown in a font whose digits have different widths: press key 7 "
                "(A) if the top one is greater, 5 (W) if equal, 9 (D) if smaller, before the time "
                "dot runs out. Reward +1 per right answer; a wrong answer or running out of time "
                "ends the episode.",
),)
