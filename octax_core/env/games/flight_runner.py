"""Flight Runner (TodPunk, Octojam 1, 2014): fly a ship between two walls. This is octax's patched
build (not the community database's), which keeps a score in V7 and a crash flag in V5.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the ship on the left, a ceiling and a floor wall
scrolling left and drifting up and down.

### Actions
0: no-op, 1: key 5 (up), 2: key 7 (left), 3: key 8 (down), 4: key 9 (right).

### Reward
Change of V7, the main loops survived: +1 per wall scroll step, about one per env step. (The
patched source indents `wallcounter += 1` under `if wallx == 0 then` beside another line, but
an Octo `if` governs one statement, so the counter runs every loop, not once per wall cycle.)

### Termination
V5 == 255 (the ship touched a wall: the patched ROM raises this flag and holds "oops" on screen
for 140 frames before restarting), or V7 == 255, the top score (the counter would wrap to 0
next), reached after about 280 steps: a game never outlasts that.

Quirks "schip": an Octo game (community database: modernChip8), tested without the VIP's
display wait or flag reset; it uses no shift, FX55/FX65 or jump-with-offset, so the modern
profile plays it as written (the "chip8" profile plays it too, paced by its display wait).
Timers: real 60 Hz: the delay timer sets a 2-frame floor on the main loop (which takes about 4
frames at 11 instructions per frame) and times the crash pause.
Start-up: 46 frames (octax: 500 instructions), walls drawn and scrolling (V7 is 9 by then).
The 4,500-step cut (5 minutes) never binds: V7 reaches 255 within about 300 steps.
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

SPECS = (GameSpec(
    id="FlightRunner",
    title="Flight Runner",
    rom_file="flightrunner.ch8",
    rom_sha1="8ca4c0cdaceb9c9e135f0a56e88adaf588e71b34",
    action_keys=(5, 7, 8, 9),
    score_fn=lambda state: state.V[7].astype(jnp.int32),
    terminated_fn=lambda state: (state.V[5] == 255) | (state.V[7] == 255),
    startup=((0, 46),),
    quirks="schip",
    max_episode_steps=4500,
    category="navigation",
    description="Fly a ship (keys 5/8 up/down, 7/9 left/right) between a scrolling ceiling and floor; "
                "reward is the change of V7 (+1 per loop survived); the game ends when the ship touches "
                "a wall or V7 reaches 255.",
),)
