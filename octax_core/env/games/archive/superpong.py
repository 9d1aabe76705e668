"""Super Pong (Octojam 8, archive "superpong"): keep the ball inside a box of four paddles.

### Observation
The screen, uint8 (frames_per_step, 32, 64): a bordered court, two vertical paddles (left and
right edges) that move together up and down, two horizontal paddles (top and bottom edges) that
move together left and right, the ball, and the score (2 digits) in the middle.

### Actions
0: no-op, 1: key 5 (vertical paddles up), 2: key 8 (down), 3: key 7 (horizontal paddles left),
4: key 9 (right); 2 pixels per ball move. (Key 6, which restarts the game, is not offered.)

### Reward
+1 per paddle hit: the change of the score the ROM shows. The ROM keeps it in VD (`:alias score vd`)
but its game-over routine reuses VD as a drawing coordinate, so the score is read from the three
BCD digits `draw-score` writes at `bcd-digits` (0x21A), which hold the last score shown.

### Termination
The ball reaching any edge of the court (x 0 or 63, y 0 or 31): the ROM jumps to `game-over`
(0x3C5..0x3E6), draws GAME OVER and waits there for key 6 (FX0A at 0x3DD), which no action holds.

Options from the archive: tickrate 30, Octo's default quirks (no shift, load/store or vblank
quirks). The ball moves every 3 frames until the score passes 5, every 2 until 10, every frame
until 15, then every step of the loop. Start-up: 5 frames (the title drawn), then key 6 held 2
frames; the title's FX0A completes when the first env step releases it, so `reset`'s random
serve (CXNN) is drawn from each episode's reset key. Episodes are cut at 4,500 steps (5 minutes).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import bcd_value, key_mask

BCD_DIGITS = 0x21A  # `bcd-digits`: hundreds, tens, ones of the shown score
GAME_OVER = (0x3C5, 0x3E7)  # `game-over`, up to `draw-game-over`

SPECS = (archive_spec(
    "superpong",
    id="SuperPong",
    rom_sha1="2c761f70a44e521ee848834cfdd2bd1646157d29",
    action_keys=(5, 8, 7, 9),
    score_fn=lambda state: bcd_value(state, BCD_DIGITS),
    terminated_fn=lambda state: (state.pc >= GAME_OVER[0]) & (state.pc < GAME_OVER[1]),
    startup=((0, 5), (key_mask(6), 2)),
    max_episode_steps=4500,
    category="timing",
    description="Move the two pairs of paddles (keys 5/8 up and down, 7/9 left and right) to keep "
                "the ball in the court; reward +1 per paddle hit; the game ends when the ball "
                "reaches an edge.",
),)
