"""Cavern (Matthew Mikolay, 2014), octax's leftward-progress edition: escape a cave to the left.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the cave walls (one 64x32 maze per level) and the
player, a one-pixel dot.

### Actions
0: no-op, 1: key 2 (up), 2: key 4 (left), 3: key 6 (right), 4: key 8 (down). The dot keeps
moving in the last direction pressed, about one pixel per 5 frames; before any key it waits.

### Reward
Change of V0, +1 per new leftmost column reached (VA holds the leftmost so far); at most the
start column (52 on level 1, 63 on the others), earned by reaching the exit on the left edge
(118 steps on level 1).

### Termination
VE (1 while playing) drops to 0 when the dot touches a wall. Leaving by the left edge wraps the
dot to the right edge of the same cave (octax's edit dropped the next-cave redraw): play
goes on with no further reward until a wall (at once on level 1).

### Levels
The seven ROMs differ in three bytes: the maze (V5 = 1, 2, 3, 4, 4, 6, 7; maze 5 unused) and
the start (x, y). Ids follow the ROM order: Cavern4 is cavern4a.ch8, Cavern5 cavern4b.ch8 (the
same maze from lower down), Cavern6 cavern5.ch8 and Cavern7 cavern6.ch8.

Quirks "chip8": the original is a COSMAC VIP program (community database: originalChip8) with
no quirk-sensitive opcode, so the profile only sets display-wait pacing; it plays identically
under "schip", a little faster. Timers: real 60 Hz; the game waits on the delay timer (1 frame)
once per move, which freezing would barely change. Start-up: 40 frames, the maze drawn (one
8x8 tile per frame, 34-37 frames) and the game waiting for a key; octax's 250 instructions (23
frames) end mid-maze under display wait. No randomness: every episode of a level is the same.
Episodes are cut at 1,000 steps; holding "left" hits a wall within 12-75 steps.
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

_LEVELS = (  # ROM file, SHA-1, maze (V5), start (x, y)
    ("cavern1.ch8", "f57c4583709022859bb7ba90cf7fc449bfaa5b26", 1, (52, 20)),
    ("cavern2.ch8", "ae59d229d6de5762549bf9bf52c23d7fa39372c7", 2, (63, 28)),
    ("cavern3.ch8", "df5e840c8db7acc6f63860246393ea2b8e2d3158", 3, (63, 8)),
    ("cavern4a.ch8", "4489020dfcd1bdc999ee68426e5af70f1901fd7a", 4, (63, 16)),
    ("cavern4b.ch8", "579846ee7e4e2175740c96bab15151b77502bda3", 4, (63, 19)),
    ("cavern5.ch8", "03364866435733eb77d9771dbaffea29c691c270", 6, (63, 3)),
    ("cavern6.ch8", "f918e843647154d0ee4ae1d900592f521d6def2c", 7, (63, 29)),
)


def _spec(level: int, rom_file: str, sha1: str, maze: int, start: tuple[int, int]) -> GameSpec:
    return GameSpec(
        id=f"Cavern{level}",
        title=f"Cavern, level {level} (maze {maze}, start {start})",
        rom_file=rom_file,
        rom_sha1=sha1,
        action_keys=(2, 4, 6, 8),
        score_fn=lambda state: state.V[0].astype(jnp.int32),
        terminated_fn=lambda state: state.V[14] == 0,
        startup=((0, 40),),
        quirks="chip8",
        max_episode_steps=1000,
        category="navigation",
        description="Steer the dot (keys 2 up, 4 left, 6 right, 8 down; it keeps going the last way "
                    "pressed) leftward through the cave; reward +1 per new leftmost column; the "
                    "episode ends when the dot touches a wall.",
    )


SPECS = tuple(_spec(level, *row) for level, row in enumerate(_LEVELS, 1))
