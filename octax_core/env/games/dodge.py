"""Dodge (octax-gym, 2026): rocks fall from the sky; move the ship to let them pass. Our own game.

The source is `roms/dodge.8o` (Octo), built into the committed `roms/dodge.ch8` by
`make roms`; the ROM store finds it in the project's `roms/` folder.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the score (3 digits) and the lives left (1 digit)
above a line, the falling rocks (4x4) and the ship on the bottom rows.

### Actions
0: no-op, 1: key 4 (ship left), 2: key 6 (ship right); 2 pixels per move.

### Reward
Change of V5, the rocks dodged: +1 each time a rock reaches the ground beside the ship.

### Termination
VE (0 while playing) becomes 1 when the last of 3 lives (V6) is lost, a rock landing on the
ship, or when the score reaches 200 (a win). The ROM then shows the score and loops on itself.

### Levels
One ROM serves the three levels, chosen on its start screen by key 1, 2 or 3 (V8): 2, 3 and 4
rocks falling 1, 2 and 3 pixels a move. `Dodge1`..`Dodge3` press that key at start-up;
`Dodge` is the middle level, `Dodge2`. Uniform random actions, 64 episodes per level:
return 16.5, 17.4 and 16.2, length 482, 286 and 202 steps (a rock lands every 21, 12 and 9
steps, and lands on a random ship about one time in six); a scripted policy that steps away
from the lowest rock above the ship scores 187, 177 and 179.

Quirks "chip8": written for it; no shift, BNNN or 8XY1-3, and I is set before every FX55/FX65,
so every profile plays it the same except for the pace (display wait ends a frame at each
sprite: about 4 frames per rock moved). Timers: real 60 Hz; the delay timer times the 48-frame
pause before the first rocks, the sound timer beeps on a hit. Start-up: 10 frames (the start
screen drawn), the level key held 3 frames, 25 frames: the play screen drawn, inside the pause,
so the first rocks' columns are drawn from each episode's reset key. Episodes are cut at 4,500
steps (5 minutes).
"""

from octax_core.env.games._own import level_specs, own_game_spec

_LEVELS = (  # level: rocks, pixels per fall
    (1, 2, 1),
    (2, 3, 2),
    (3, 4, 3),
)
DEFAULT_LEVEL = 2


def _spec(game_id: str, level: int, rocks: int, fall: int):
    return own_game_spec(
        game_id, level,
        title=f"Dodge, level {level} ({rocks} rocks, {fall} pixel{'s' if fall > 1 else ''} per move)",
        rom_file="dodge.ch8",
        rom_sha1="b18d01a319230c9d99c24a19c46bef6c81464269",
        action_keys=(4, 6),
        category="reaction",
        description=f"Move the ship (keys 4 left, 6 right) to dodge {rocks} falling rocks; reward +1 "
                    "per rock that lands beside the ship; the game ends when 3 rocks have hit it "
                    "(VE == 1) or at 200 rocks dodged.",
    )


SUITE = "ours"
SPECS = level_specs("Dodge", _LEVELS, DEFAULT_LEVEL, _spec)
