"""Space Flight, octax's single-life edition: fly once across an asteroid field, left to right.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the ship (3x2 pixels) on the left, the asteroids
as single pixels in eight columns (x = 10..62).

### Actions
0: no-op, 1: key 1 (up), 2: key 4 (down). The ship always moves 2 pixels right per move (one
move per 6-7 frames, 53 steps for a crossing); the key held moves it one row.

### Reward
Change of V0, +1 per move survived: 30 for a full crossing.

### Termination
V9 (lives, 1) equals 0, a collision, or VC (ship x) >= 0x3E, the ship at the right edge: the
paper's rule, `(V[9] == 0) | (V[12] >= 0x3E)`. With the default 4 frames per step a crossing
ends on step 53.

Where the ROM and the paper disagree: the ROM holds VC at 0x3E for only 2 frames, then starts
the ship on the left of a new field (VA, 4 at the start, counts the crossings down), and the
paper's rule is read once per step, after its last frame. The 2 frames are frames 212-213 after
start-up at every level, whatever the keys (measured), so steps of 1 to 4 frames see them (212
= 4 x 53) but other `frames_per_step` values can miss them (5 to 52 do): the crossing then
does not end the episode, which runs on into further fields until a collision or the step cut
(V0 wraps past 255). With 5 frames per step, SpaceFlight1's crossing passes unseen in step 43
and no-ops then crash at the next field's first move, step 56. To end on every crossing
whatever the step length, use instead
`terminated_fn=lambda s: (s.V[9] == 0) | (s.V[12] >= 0x3E) | (s.V[10] != 4)` in a
`dataclasses.replace` of this spec.

### Levels
The ten ROMs differ in one byte, the level (VB = 1..10), which sets the number of asteroids:
30, 40, 50, 55, 60, 65, 70, 75, 80, 85.

Quirks "chip8": the original is a COSMAC VIP program (community database: originalChip8) with
no quirk-sensitive opcode; the profile sets display-wait pacing (one frame per asteroid drawn)
and the game also plays under "schip". Timers: real 60 Hz; the game waits 5 frames per move.
Start-up: 34 + (asteroids) frames, the field drawn and the ship about to make its first move;
octax's 300 instructions (28 frames) stop mid-field. The field is drawn at start-up, from a
fixed seed, so every episode of a level is the same field (as in octax). Episodes are cut at
500 steps; with 4 frames per step one always ends within 53 (not so with other step lengths,
see above).
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

_LEVELS = (  # ROM file, SHA-1, asteroids
    ("space_flight1.ch8", "1086fe15b4608581c8715618f303af911813dc8e", 30),
    ("space_flight2.ch8", "b5de356579b3b4e83769ff21c734a0de4a57e40c", 40),
    ("space_flight3.ch8", "f68a294a869828abf2a5f77a42cf2aa40377e742", 50),
    ("space_flight4.ch8", "17332012fbe8840277c4b01162746906ef29633f", 55),
    ("space_flight5.ch8", "05e8e285872740154d60f3743e5a64a9f8c1d6c3", 60),
    ("space_flight6.ch8", "e8510d6c4ea1180f9c5dc2fcd1372518ae7f539e", 65),
    ("space_flight7.ch8", "dc70a389b9a47bbb125e11fc2b2751ce1a7a87e1", 70),
    ("space_flight8.ch8", "7f14117b1e138707ebf80ae9c5bd571d1ca46dde", 75),
    ("space_flight9.ch8", "6e73aec0c742fb20e057852cfce7f83b808e4fdb", 80),
    ("space_flight10.ch8", "621dc9c9e7ecafc00ad73f5d3421407ae7b12be2", 85),
)


def _terminated(state):
    return (state.V[9] == 0) | (state.V[12] >= 0x3E)  # the paper's rule, exactly


def _spec(level: int, rom_file: str, sha1: str, asteroids: int) -> GameSpec:
    return GameSpec(
        id=f"SpaceFlight{level}",
        title=f"Space Flight, level {level} ({asteroids} asteroids)",
        rom_file=rom_file,
        rom_sha1=sha1,
        action_keys=(1, 4),
        score_fn=lambda state: state.V[0].astype(jnp.int32),
        terminated_fn=_terminated,
        lives_fn=lambda state: state.V[9].astype(jnp.int32),
        startup=((0, 34 + asteroids),),  # frames the title and one asteroid per frame take
        quirks="chip8",
        max_episode_steps=500,
        category="navigation",
        description="Steer the ship (keys 1 up, 4 down) as it flies right through the asteroid "
                    "field; reward +1 per move survived; the episode ends at the first collision "
                    "or when the ship reaches the right edge.",
    )


SPECS = tuple(_spec(level, *row) for level, row in enumerate(_LEVELS, 1))
