"""Flutter By (Octojam 6, archive "flutterby"): keep a butterfly aloft on the nectar of passing flowers.

### Observation
The screen, uint8 (frames_per_step, 64, 128), XO-CHIP planes as values 0..3: the butterfly
flapping near the left edge, the ground and flowers (stems of random height, the nectar drawn on
plane 2) scrolling in from the right, and at the top one dot whose x position is the energy left
(`:alias score vb`).

### Actions
0: no-op, 1: key 5 (Octo's W: rise), 2: key 8 (S: sink). The choice sticks: `input` sets
`control` (v6) only when a key is down, so no-op keeps the butterfly rising (1 pixel a loop) or
sinking (2 pixels) as it last did; on top of that it drifts by a random -2..+1 pixels each way.
(The game reads no other keys; the source's comment about ASD is a leftover of Octo's template.)

### Reward
+1 for every step the butterfly survives after (`survival_reward`). The ROM keeps no score, only
the energy in vb: -1 at every scroll of the world, +8 (to at most 127) when the butterfly's
`test` sprite touches a flower's nectar on plane 2 (`dotest`), so its change summed over an
episode is always -64 at the end; the flowers reached show instead as time survived.

### Termination
Energy 0 (`gameovercheck`, called after every scroll): `gameover` (0x380..0x38B) plays a sad
tone and jumps to `start`, which runs `setup` and `drawlogo` (the calls at 0x200..0x203) again
before a new game; vb at 0 or the pc in any of those (or a routine they called) is the end.

Options from the archive: XO-CHIP (hires, planes, `audio`), tickrate 7: a game loop is about 80
instructions, so it runs about once every 12 frames (the delay timer's 3 frames never bind), and
the world scrolls every `sexdrive` + 1 loops (2 to 10: faster the more energy). Octo's default
quirks, its colours. Start-up: 90 frames, past `setup` and the logo's 64-frame pause; the flight's
random drift and every flower (`random`) are drawn from each episode's reset key. Without
flowers a flight lasts about 1,800 steps (64 scrolls, the last 32 eleven loops apart); episodes
are cut at 4,500 steps.
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, register_value

START_CALLS = (0x200, 0x204)  # `start`: call setup, call drawlogo
GAME_OVER = (0x380, 0x38C)  # `gameover`


def _over(state):
    return ((register_value(state, 11) == 0) | in_routine(state, *START_CALLS)
            | in_routine(state, *GAME_OVER))


SPECS = (archive_spec(
    "flutterby",
    id="FlutterBy",
    rom_sha1="a4a9351775b2a64bbd14e3980968db19c254a988",
    action_keys=(5, 8),
    score_fn=lambda state: 0,
    survival_reward=1.0,
    terminated_fn=_over,
    startup=((0, 90),),
    max_episode_steps=4500,
    category="timing",
    description="Steer the butterfly up (key 5) or down (key 8; the choice sticks) through the "
                "flowers' nectar, which refills the energy that every scroll of the world drains; "
                "reward +1 per step survived (the ROM keeps no score); the game ends when the "
                "energy runs out.",
),)
