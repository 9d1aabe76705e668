"""Into the GarlicScape (Octojam 7, archive "garlicscape"): a roguelike; collect aliums, avoid moths.

### Observation
The screen, uint8 (frames_per_step, 64, 128), XO-CHIP pixel codes 0..3 (plane 1 + 2 x plane 2):
a 16x9 board of 7x7 tiles in hires, the player, llamas, moths and roaches, the health hearts on
the left and the score (2 digits) on the right.

### Actions
0: no-op, 1: key 7 (Octo's A: left), 2: key 9 (D: right), 3: key 5 (W: up), 4: key 8 (S: down).
A move is buffered (`buffer-input`) and taken on the next 5-frame turn; walking into a mob bumps
it. Left out: key 6 (E, dismisses the end screens, which would restart the game) and the source's
debug keys 1 (hurt the player) and 2 (add a point), which it says to remove before shipping.

### Reward
+1 per alium collected: the change of `player-score` (RAM 0x205), which `score-increment` adds
to; the goal is 15 (`SCORE_GOAL`) and the last one, on map 3, wins.

### Termination
`player-health` (RAM 0x204, 3 at the start, `MAX_HEALTH`) reaching 0, which shows GAME OVER, or
the win screen: both then wait in `wait-for-space` (pc 0x275..0x284) for key 6, which no action
holds, and `jump main` would start over. Lives: `player-health`.

Options from the archive: XO-CHIP, tickrate 1000 (the source asks for 500-1000), Octo's default
quirks, its own four colours. A turn is 5 frames (`delay := 5`). Start-up: 1 frame, which runs
`main` through `health-reset` (the ROM's initial health byte is 0), then key 9 held 120 frames:
the player walks right out of the title map (map 0, nothing to collect or fight) into map 1, so
every episode starts where the game is played; that map is the same in every episode, and the
mobs' moves and later maps' random layouts (`board-unpack`) come from each episode's reset key.
Random play rarely reaches an alium (none in 1,600 steps), so the test checks the score through
the source's debug key 2. At 1,000 XO-CHIP instructions a frame this is one of the slowest games
(see docs/gallery.md). Episodes are cut at 4,500 steps (5 minutes).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import key_mask, ram_value

PLAYER_HEALTH, PLAYER_SCORE = 0x204, 0x205
WAIT_FOR_SPACE = (0x275, 0x285)  # `wait-for-space`: the game-over and win screens wait here


def _ended(state):
    waiting = (state.pc >= WAIT_FOR_SPACE[0]) & (state.pc < WAIT_FOR_SPACE[1])
    return (ram_value(state, PLAYER_HEALTH) == 0) | waiting


SPECS = (archive_spec(
    "garlicscape",
    id="IntoTheGarlicScape",
    rom_sha1="b693e60f161e69c98b0bb2bc1761cf434f8fbb0e",
    action_keys=(7, 9, 5, 8),
    score_fn=lambda state: ram_value(state, PLAYER_SCORE),
    terminated_fn=_ended,
    lives_fn=lambda state: ram_value(state, PLAYER_HEALTH),
    startup=((0, 1), (key_mask(9), 120)),
    max_episode_steps=4500,
    category="navigation",
    description="Walk the GarlicScape (keys 7/9/5/8: left, right, up, down) collecting aliums and "
                "bumping moths and roaches away; llamas heal. Reward +1 per alium; the episode ends "
                "when health (3) runs out or the 15th alium wins.",
),)
