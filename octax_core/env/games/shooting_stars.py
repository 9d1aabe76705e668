"""Shooting Stars (Philip Baltzer, 1978): steer a small ball around a big one while stars streak by.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the player's small ball (it wraps at the edges), a
big ball in the middle, one star in flight; after each point, the score's last hex digit.

### Actions
0: no-op, 1: key 2 (up), 2: key 8 (down), 3: key 4 (left), 4: key 6 (right).

### Reward
Change of the score, V0 capped: 0 when V0 > 128. V0 rises by one when the player's ball runs
into something (a star or the big ball) and falls by one (never below 0) when a star runs into
the player's ball; each point starts a new round. V0 passes through 255 for two frames on the
way from 0 back to 0, which the cap hides. Past 128 points the cap drops the score to 0 (reward
-128): kept as published; unlikely within one default episode, as every point costs a 16-step
pause plus the trip to the next collision.

### Termination
Never: the game has no end; episodes are only truncated.

Quirks "chip8": an original COSMAC VIP program (community database: originalChip8) using no
quirk-sensitive opcode; the profile only sets the VIP's display-wait pacing. Timers: real 60 Hz:
the delay timer times the 64-frame pause after each point (octax zeroes it, skipping
the pause).
Start-up: 2 frames, until the balls are drawn (octax uses none). Episodes are cut at 4,500
steps (5 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec


def _score(state):
    v0 = state.V[0].astype(jnp.int32)
    return jnp.where(v0 > 128, 0, v0)


SPECS = (GameSpec(
    id="ShootingStars",
    title="Shooting Stars",
    rom_file="Shooting Stars [Philip Baltzer, 1978].ch8",
    rom_sha1="443550abf646bc7f475ef0466f8e1232ec7474f3",
    action_keys=(2, 8, 4, 6),
    score_fn=_score,
    terminated_fn=lambda state: jnp.zeros((), jnp.bool_),
    startup=((0, 2),),
    quirks="chip8",
    max_episode_steps=4500,
    category="reaction",
    description="Steer a small ball (keys 2/8/4/6) while stars streak across the screen; reward is "
                "the change of V0 (capped to 0 above 128): +1 when the ball runs into a star or the big "
                "ball, -1 when a star runs into it; the game never ends (episodes are truncated).",
),)
