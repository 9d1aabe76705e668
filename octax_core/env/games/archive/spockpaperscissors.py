"""Spock Paper Scissors (Octojam 7, archive "spockpaperscissors"): rock-paper-scissors-lizard-Spock vs the CPU.

### Observation
The screen, uint8 (frames_per_step, 32, 64): your score (left) and the CPU's (right), each 3
digits, and after a throw both hands (yours left, the CPU's right) with a + over the winner's
score or = over both on a tie.

### Actions
0: no-op, 1: key 7 (Octo's A: rock), 2: key 8 (S: paper), 3: key 9 (D: scissors), 4: key A
(Z: lizard), 5: key 0 (X: Spock). `turn_user` reads them with FX0A (0x57E): a throw counts
once, when its key is released, so a key held for several steps is one throw.

### Reward
+1 for a round you win, -1 for a round the CPU wins, 0 for a tie: the change of
`score_user - score_cpu` (V4 and V5, `:alias score_user v4`, `:alias score_cpu v5`), which
`won_user` and `won_cpu` each raise by 1 (rock beats lizard and scissors, paper beats Spock and
rock, scissors beat lizard and paper, lizard beats Spock and paper, Spock beats scissors and
rock). The CPU throws after you (`turn_cpu`: `random 0xFF` cut at 0x32, 0x65, 0x98, 0xCB, so
each hand about 1/5), without looking at your throw: every throw wins, loses and ties with
about the same chances (2/5, 2/5, 1/5), so every policy's expected return is about 0; the game
measures luck.

### Termination
None: the game has no end (`main` loops on `cycle` forever) and no lives, so episodes are only
cut, at 4,500 steps (5 minutes, about 220 rounds of 20 steps; V4 and V5 are 8-bit and would wrap
after 255 wins, which a much longer cut could reach).

Options from the archive: tickrate 15, Octo's default quirks, its colours. After each round
`dt` holds the result on screen for 70 frames of the delay timer (real timers: about 18 steps)
before the hands are erased and the next FX0A. Start-up: 40 frames (the title drawn), key 1
held 2 frames (its FX0A), 40 frames (the second title), key 1 again, then 40 frames (the
scores drawn, the game waits in `turn_user`); key 1 is not an action. Every CPU throw is drawn
from the episode's reset key.
"""

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import key_mask, register_value

SCORE_USER, SCORE_CPU = 4, 5  # V4, V5

SPECS = (archive_spec(
    "spockpaperscissors",
    id="SpockPaperScissors",
    rom_sha1="b66f55f83eb264d2b73c0b4ac81ea5044bf73138",
    action_keys=(7, 8, 9, 0xA, 0),
    score_fn=lambda state: register_value(state, SCORE_USER) - register_value(state, SCORE_CPU),
    terminated_fn=lambda state: jnp.zeros((), jnp.bool_),  # the game has no end
    startup=((0, 40), (key_mask(1), 2), (0, 40), (key_mask(1), 2), (0, 40)),
    max_episode_steps=4500,
    category="reaction",
    description="Throw rock (key 7), paper (8), scissors (9), lizard (A) or Spock (0) against the "
                "CPU's random throw; reward +1 per round won, -1 per round lost; the game has no "
                "end, so episodes are only cut.",
),)
