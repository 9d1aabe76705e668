"""Slippery Slope (Octojam 5, archive "slipperyslope"): slide across the ice to the goal, level by level.

### Observation
The screen, uint8 (frames_per_step, 32, 64): a bordered 12x6 board of 5x5 tiles: walls, holes,
fixed mirrors, flip-flop mirrors (they turn each time they are crossed) and rough ground that stops
a slide; the player (facing one of four ways) and the sparkling goal.

### Actions
0: no-op, 1: key 9 (Octo's D: slide right), 2: key 5 (W: up), 3: key 7 (A: left), 4: key 8 (S:
down). A slide goes on, a tile every 5 frames, until a wall, the board's edge, rough ground or the
goal; mirrors turn it. (Key 6, Octo's E, which restarts the level, is not offered; the game reads
no other keys.)

### Reward
+1 per level solved: the change of `:alias level v6` (the level number, 1..10) less 1. Two
corrections keep it from spiking: `level-unpack`'s bulk copy (`load vb`, 0x26B..0x2AB) reuses v6,
so there the level is read from its copy in `level-unpack-stash` (0x255 + 6); and on the last level
the ROM sets `level` back to 1 as it draws THE END, so the score is read as 10 from then on (the
end is also the termination below). The step counter the ROM shows (`step-level`) is not used:
fewer moves is better there, but it never ends the game.

### Termination
Solving level 10 (`FINAL_LEVEL`): `main`'s MODE-NEXT branch takes its `if level == FINAL_LEVEL`
arm (0x796..0x83B: `level := 1`, `draw-gameover`, the step counter reset), then `level-unpack`,
`wait-key` and `load-level` (0x866..0x8B7) restart at level 1; the pc (or a return address) in
either range with `level` 1 is the end (only the end runs them with `level` 1: solving level 1
goes through the `else` arm, 0x83C, which makes it 2). A hole (`tile-hole`) is no game over: it
restarts the level (MODE-RESET), its flip-flops as the level began.

Options from the archive: tickrate 30, Octo's default quirks, its colours. Start-up: the title
screen is level 0, a board whose player slides right into its goal: 2 frames, key 9 held 44
frames (the 8-tile slide), 20 frames (the LEVEL 1 card drawn), key 8 held 1 frame to leave
the card (`wait-key`), 30 frames (`load-level` draws the board; the key is up before the board's
first `poll-player`). The game draws no random numbers that matter (only the card's sliding
decoration), so every episode starts from the same board and only the policy varies it. A puzzle
with no way to lose: episodes are cut at 4,500 steps (5 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, ram_value, register_value

FINAL_LEVEL = 10
STASH = 0x255  # `level-unpack-stash`: v0..vF as `level-unpack` found them
UNPACKING = (0x26B, 0x2AB)  # `level-unpack` after its `save vf`, up to its `load vf`
THE_END = (0x796, 0x83C)  # the `if level == FINAL_LEVEL` arm of `main`'s MODE-NEXT branch
NEXT_LEVEL = (0x866, 0x8B8)  # `level-unpack`, `wait-key`, `load-level` after either arm


def _level(state):
    """`level` (v6), or its copy in the stash while `level-unpack`'s bulk copy reuses v6."""
    unpacking = (state.pc >= UNPACKING[0]) & (state.pc <= UNPACKING[1])
    return jnp.where(unpacking, ram_value(state, STASH + 6), register_value(state, 6))


def _the_end(state):
    level = _level(state)
    return (level == 1) & (in_routine(state, *THE_END) | in_routine(state, *NEXT_LEVEL))


def _levels_solved(state):
    return _the_end(state) * FINAL_LEVEL + (1 - _the_end(state)) * (_level(state) - 1)


SPECS = (archive_spec(
    "slipperyslope",
    id="SlipperySlope",
    rom_sha1="9d834860f455aec7e95fb886984497e5be501610",
    action_keys=(9, 5, 7, 8),
    score_fn=_levels_solved,
    terminated_fn=_the_end,
    startup=((0, 2), (key_mask(9), 44), (0, 20), (key_mask(8), 1), (0, 30)),
    max_episode_steps=4500,
    category="planning",
    description="Slide the skater across the ice (keys 9/5/7/8: right, up, left, down; a slide stops "
                "only at walls, edges, rough ground or the goal; mirrors turn it, holes restart the "
                "level) to reach each level's goal; reward +1 per level solved; the game ends after "
                "the tenth level.",
),)
