"""Br8kout (Octojam 1, archive "br8kout"): a one-pixel ball, a paddle and seven rows of bricks.

### Observation
The screen, uint8 (frames_per_step, 32, 64): 7 rows of 7 bricks (6x1 pixels at x 5, 13, .., 53 on
rows 2, 4, .., 14), the ball (one pixel) and the paddle (6x1, row 30). No score is drawn.

### Actions
0: no-op, 1: key 7 (Octo's A: paddle 4 pixels left), 2: key 9 (D: right), read once per pass of
the main loop (`paddlex` VD wraps around the screen).

### Reward
+1 per brick broken. The ROM keeps no count: a brick exists only as its pixels on the screen,
and `destroy-brick` erases one (XOR) when the ball's sprite collides with it. The score is 49
minus the bricks still standing, read from the screen (a brick stands while at least 3 of its 6
pixels are lit: the ball over it lights at most one and unlights at most one), and 0 before
`main` has drawn the wall (pc 0x200 or in `main` up to its loop, 0x29F..0x2B4, with the calls
it makes). It never goes down during an episode.

### Termination
A miss: the ball on row 30 still heading down (`ballvy` V8 = 1 once `move-ball` has settled its
collision: pc outside 0x269..0x27E and `ball-collide`/`destroy-brick` 0x243..0x262) will reach
row 31 on the next move, where `move-ball` calls `reset` (0x285..0x292), which clears the screen,
puts the ball back at (30, 20) and redraws every brick. The ROM has no game over (the readme's
"DIE"); `bally` (VA) = 31 or any step inside `reset` (or a routine it called) also ends the
episode. The end is seen at least one main-loop pass (4+ frames) before `reset` clears the
screen, so with frames_per_step at most 4 (the default) the last step's reward counts the bricks
of that life; a larger frames_per_step can end a step past the clear (the episode still ends,
inside `reset`'s ~50 frames, but that step's reward is then meaningless).

Options from the archive: CHIP-8, tickrate 7, its colours, Octo's default quirks. The ball moves
1 pixel each way per loop pass, which `sync` holds to at least 4 frames (delay timer). No
start-up: the first 16 steps of every episode run `main` (the wall drawn), whose `random` picks
the ball's first horizontal direction from the episode's reset key; the ball starts off the
right edge (`ballx` = 64, drawn wrapped at x 0) and, heading right, crosses the screen wrapping
until `ballx` wraps to 0. Nothing else is random. Episodes are cut at 4,500 steps (5 minutes).
"""

import jax.numpy as jnp

from octax_core.emulator.state import unpack_screen
from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, register_value

BALL_Y, BALL_VY = 10, 8  # VA `bally`, V8 `ballvy`
MOVE_CHECKS = (0x269, 0x27F)  # `move-ball` after `bally += ballvy`, before its collision is settled
BALL_COLLIDE = (0x243, 0x263)  # `ball-collide` (flips ballvy), `destroy-brick`
RESET = (0x285, 0x293)  # `reset`
SETUP = (0x29F, 0x2B5)  # `main` up to its loop (`draw-bricks` among its calls)
BRICK_ROWS = tuple(range(2, 16, 2))  # `draw-bricks`: v0 = 2, 4, .. 14
BRICK_XS = tuple(range(5, 56, 8))  # v1 = brickxoffset 5, 13, .. 53
BRICKS = len(BRICK_ROWS) * len(BRICK_XS)  # 49


def bricks_standing(state):
    """The bricks whose 6 pixels are at least half lit."""
    rows = unpack_screen(state.screen, on=1, dtype=jnp.int32)[jnp.array(BRICK_ROWS)]
    lit = jnp.stack([rows[:, x:x + 6].sum(axis=1) for x in BRICK_XS], axis=1)
    return (lit >= 3).sum()


def _score(state):
    setup = in_routine(state, *SETUP) | (state.pc == 0x200)
    return jnp.where(setup, 0, BRICKS - bricks_standing(state))


def _over(state):
    y, vy = register_value(state, BALL_Y), register_value(state, BALL_VY)
    settled = ~in_routine(state, *MOVE_CHECKS) & ~in_routine(state, *BALL_COLLIDE)
    return (settled & (y == 30) & (vy == 1)) | (y == 31) | in_routine(state, *RESET)


SPECS = (archive_spec(
    "br8kout",
    id="Br8kout",
    rom_sha1="31fc1c53cc610a9f4b9c5705c5a0f33fc028d123",
    action_keys=(7, 9),
    score_fn=_score,
    terminated_fn=_over,
    max_episode_steps=4500,
    category="timing",
    description="Move the paddle (keys 7 left, 9 right) under the ball to break the wall of 49 "
                "bricks; reward +1 per brick broken (read from the screen: the ROM keeps no "
                "score); the game ends when the ball gets past the paddle.",
),)
