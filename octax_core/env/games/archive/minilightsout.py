"""Mini Lights Out (Octojam 6, archive "mini-lights-out"): switch off a 4x4 torus of lights.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the 4x4 grid (8x8 cells at x 16, 24, 32, 40 and
y 0, 8, 16, 24; a light that is on is a filled 6x6 square, one that is off a hollow 8x8 frame) and
the moves made (2 digits, right). After the end: YOU WIN, or the LIGHTS OUT title after a loss.

### Actions
0: no-op; 1..16: the light at row (i - 1) // 4, column (i - 1) % 4, by its key (the ROM's
`keys` table): 1 2 3 C / 4 5 6 D / 7 8 9 E / A 0 B F. `game-loop` reads a key with FX0A, which
completes when the key is released, so a press acts on the next step that holds another action
(a no-op, say). Pressing a light toggles it and its four neighbours, wrapping around the edges;
only a light that is on may be pressed (`toggle` buzzes and ignores the rest, and such a press
is not counted as a move).

### Reward
+1 when the puzzle is solved (every light off), 0 otherwise: one puzzle per episode. `check-win`
tests every light after each move; when none is on it falls through to the win screen (0x31E..
0x34F), whose step scores 1. The ROM counts moves (`steps` VD, shown via BCD at `steps-bcd`
0x433) but keeps no score, so the score reads 1 inside the win screen, and afterwards (the title
and `init-game`, 0x200..0x2EF) where the moves shown are neither 0 (a new game's) nor 99 (what
`steps-bcd` holds after a loss). The win screen lasts 5 frames, so with frames_per_step at most
5 (the default is 4) the first step of the end lies in it; with more, a win in exactly 99 moves
first seen after it would score 0.

### Termination
The puzzle solved (the win screen, then the title) or lost: the 100th counted move makes `steps`
(VD) 100 and `jump main` redraws the title. Either way the ROM waits at the title
(`title-screen`, 0x238..0x2AD) for any key, which would start a new puzzle (`init-game`); as
every key is an action, the episode ends earlier: on VD = 100, in `main`/`title-screen`
(0x200..0x2AD), in the win screen, or in `init-game` (0x2AE..0x2EF) with a nonzero move count
in `steps-bcd` (a new puzzle after one that ended; this episode's own puzzle is set up while it
still holds 0). From the win or the 100th move to that new puzzle's first key wait is at least
33 frames, even with a key held at the title (measured frame by frame).

Options from the archive: CHIP-8, tickrate 7 ("touchInputMode" does not apply), Octo's default
quirks and colours. After each move the next key is read 10 to 13 frames later (about 3 steps
at the default 4 frames per step; more when few lights are on, as `check-win` stops at the
first light it finds on); the first puzzle's grid takes 27 frames to draw. Start-up: 10
frames (the title drawn), then key 1 held 1 frame, which jumps to `init-game` just before its
two `random 255` draws (vc, ve: the grid's bits, drawn again while vc & ve is 0), so every
episode's puzzle comes from its reset key. Episodes are cut at 4,500 steps (5 minutes); the
100-move limit ends any that keeps making moves long before.
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import bcd_value, in_routine, key_mask, register_value

STEPS = 13  # VD `steps`
STEPS_BCD = 0x433  # `steps-bcd`: hundreds, tens, ones of the moves last drawn
TITLE = (0x200, 0x2AE)  # `main` (the logo) and `title-screen`
INIT_GAME = (0x2AE, 0x2F0)  # `init-game`, with its `draw-steps`
WIN = (0x31E, 0x350)  # the end of `check-win` when no light is on: YOU WIN, then `jump title-screen`
LIGHT_KEYS = (0x1, 0x2, 0x3, 0xC, 0x4, 0x5, 0x6, 0xD, 0x7, 0x8, 0x9, 0xE, 0xA, 0x0, 0xB, 0xF)


def _won(state):
    shown = bcd_value(state, STEPS_BCD)
    after = in_routine(state, TITLE[0], INIT_GAME[1]) & (shown != 0) & (shown != 99)
    return in_routine(state, *WIN) | after


def _over(state):
    shown = bcd_value(state, STEPS_BCD)
    return ((register_value(state, STEPS) == 100) | in_routine(state, *TITLE) | in_routine(state, *WIN)
            | (in_routine(state, *INIT_GAME) & (shown != 0)))


SPECS = (archive_spec(
    "mini-lights-out",
    id="MiniLightsOut",
    rom_sha1="a3f0eae99964b873eb1adbd3e8bcb90d15f762c3",
    action_keys=LIGHT_KEYS,
    score_fn=lambda state: _won(state).astype("int32"),
    terminated_fn=_over,
    startup=((0, 10), (key_mask(1), 1)),
    max_episode_steps=4500,
    category="planning",
    description="Press lights that are on (16 actions, one per light of the 4x4 grid) to toggle "
                "them and their four neighbours on a torus until every light is off; reward +1 "
                "when the puzzle is solved; the game ends when it is solved or after 100 moves.",
),)
