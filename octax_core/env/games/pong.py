"""Pong (1 player): the left paddle against a computer paddle on the right.

### Observation
The screen, uint8 (frames_per_step, 32, 64): both paddles, the ball and the score digits
(player, computer) on top.

### Actions
0: no-op, 1: key 1 (paddle up), 2: key 4 (paddle down).

### Reward
Change of V14 // 10 - V14 % 10: V14 holds the player's points in its tens digit and the
computer's in its ones digit, so +1 when the player scores and -1 when the computer does.

### Termination
Either digit of V14 reaches 9. A paddle held at the top loses 0-9 in about 750-1,000 steps.

Quirks "chip8": an original CHIP-8 program (community database: originalChip8); the quirks
that differ do not change its logic (no shift or BNNN; VF after 8XY2 and I after FX65 are never
read), so the profile only sets the VIP's display-wait pacing: a loop of six sprites takes six
frames (under "schip" the same game runs about twice as fast). Timers: real 60 Hz; the game
waits 96 frames (24 steps) before each serve. Start-up: 95 frames (octax: none), the paddles
and score drawn and 5 frames before the first serve, whose height is drawn from the reset key.
Episodes are cut at 4,500 steps (5 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec


def _score(state):
    points = state.V[14].astype(jnp.int32)
    return points // 10 - points % 10


def _terminated(state):
    points = state.V[14].astype(jnp.int32)
    return (points // 10 == 9) | (points % 10 == 9)


SPECS = (GameSpec(
    id="Pong",
    title="Pong (1 player)",
    rom_file="Pong (1 player).ch8",
    rom_sha1="607c4f7f4e4dce9f99d96b3182bfe7e88bb090ee",
    action_keys=(1, 4),
    score_fn=_score,
    terminated_fn=_terminated,
    startup=((0, 95),),
    quirks="chip8",
    max_episode_steps=4500,
    category="timing",
    description="Move the left paddle (keys 1 up, 4 down) to return the ball; reward +1 per point "
                "won and -1 per point lost; the game ends when either side reaches 9 points.",
),)
