"""Flak (octax-gym, 2026): planes cross the sky; move the gun and shoot them down. Our own game.

The source is `roms/flak.8o` (Octo), built into the committed `roms/flak.ch8` by `make roms`;
the ROM store finds it in the project's `roms/` folder.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the score (3 digits) and the lives left (1 digit)
above a line, the planes (8x3, flying left or right at random rows), the shell (1x4) and the
gun on the bottom rows.

### Actions
0: no-op, 1: key 4 (gun left), 2: key 6 (gun right), 3: key 5 (fire; one shell in the air at
a time, climbing 4 rows a move, so a fast plane must be led).

### Reward
Change of V5, the planes shot down: +1 per hit.

### Termination
VE (0 while playing) becomes 1 when the last of 3 lives (V6) is lost, a plane getting across
the screen, or when the score reaches 200 (a win). The ROM then shows the score and loops on
itself.

### Levels
One ROM serves the three levels, chosen on its start screen by key 1, 2 or 3: 1, 2 and 3
planes flying 1, 2 and 3 pixels a move. `Flak1`..`Flak3` press that key at start-up; `Flak`
is the middle level, `Flak2`. Uniform random actions, 64 episodes per level: return 12.2,
11.5 and 10.5, length 903, 468 and 311 steps (a random gun brings down about four planes in
five); a scripted policy that leads the nearest plane and fires wins (200) on every level,
one hit every 21, 15 and 13 steps.

Quirks "chip8": written for it; no shift, BNNN or 8XY1-3, and I is set before every FX55/FX65,
so every profile plays it the same except for the pace (display wait ends a frame at each
sprite: about 5 frames per plane moved). Hits are found by the sprite collision flag, then
checked against each plane's box. Timers: real 60 Hz; the delay timer times the 48-frame pause
before the first planes, the sound timer beeps when a plane gets across. Start-up: 10 frames
(the start screen drawn), the level key held 3 frames, 25 frames: the play screen drawn,
inside the pause, so the first planes are drawn from each episode's reset key. Episodes are
cut at 4,500 steps (5 minutes).
"""

from octax_core.env.games._own import level_specs, own_game_spec

_LEVELS = (  # level: planes, pixels per move
    (1, 1, 1),
    (2, 2, 2),
    (3, 3, 3),
)
DEFAULT_LEVEL = 2


def _spec(game_id: str, level: int, planes: int, speed: int):
    return own_game_spec(
        game_id, level,
        title=f"Flak, level {level} ({planes} plane{'s' if planes > 1 else ''}, "
              f"{speed} pixel{'s' if speed > 1 else ''} per move)",
        rom_file="flak.ch8",
        rom_sha1="7bb42d4abb5f4ed443fc767a67689a7b96e66430",
        action_keys=(4, 6, 5),
        category="timing",
        description="Move the gun (keys 4 left, 6 right) and fire (key 5) at the planes crossing "
                    "the sky; reward +1 per plane shot down; the game ends when 3 planes have "
                    "got across (VE == 1) or at 200 hits.",
    )


SUITE = "ours"
SPECS = level_specs("Flak", _LEVELS, DEFAULT_LEVEL, _spec)
