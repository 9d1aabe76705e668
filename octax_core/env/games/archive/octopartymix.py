"""Octo Party Mix! (Octojam 7, archive "OctoPartyMix"): survive a gauntlet of random microgames.

### Observation
The screen, uint8 (frames_per_step, 64, 128), XO-CHIP pixel codes 0..3 (plane 1 + 2 x plane 2),
lores (each pixel a 2x2 block): between rounds the lives left as dancing octopuses and the score;
then the round's instruction (DIG!, HAT!, FOLLOW ME!) and its microgame with a burning fuse.

### Actions
0: no-op, 1: key 6 (Octo's E: dig, drop the hat), 2: key 5 (W: up), 3: key 9 (D: right),
4: key 8 (S: down), 5: key 7 (A: left); "Every microgame uses E/6 or WASD/5789" (the source).
Dig! needs E pressed and released once per shovel (`difficulty` digs); Hat! drops the hat on the
moving octopus with E; Follow me! repeats a dance of W, D, S, A.

### Reward
+1 per round reached: the change of `score` (RAM 0x2F6, three digits ones first, as
`incrementScore` keeps them), which the ROM increments on the screen before every microgame,
whether or not the last one was won; a lost microgame costs a life as well, so a return counts
the rounds an agent lasted.

### Termination
No lives left: `lives` (VB, `:alias lives vb`, 4 at the start) reaching 0 after `youFailed`; the
ROM then shows GAME OVER and the final score until E is pressed and released (a restart, which
the episode never reaches). Lives: VB.

Options from the archive: XO-CHIP, tickrate 1000 ("intended to run at 1000 cycles/Frame"),
Octo's default quirks, its own colours. The ROM paces itself with busy loops (`timer := 255`
counted down per loop pass), not the delay timer, so its speed depends on the tickrate.
Every 3 rounds (`gamesToIncreaseDiff`) the difficulty rises. Start-up: 30 frames (the title
drawn), key 6 held 3 frames then released 1 frame (the title's press-and-release), so the first
round's microgame (`random 0b11`) and all after are drawn from each episode's reset key. One of
the slowest games here (1,000 XO-CHIP instructions a frame; see docs/gallery.md). Episodes are
cut at 4,500 steps (5 minutes).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import key_mask, ram_value

SCORE = 0x2F6  # `score`: ones, tens, hundreds
LIVES = 11  # VB


def _score(state):
    return ram_value(state, SCORE) + 10 * ram_value(state, SCORE + 1) + 100 * ram_value(state, SCORE + 2)


SPECS = (archive_spec(
    "OctoPartyMix",
    id="OctoPartyMix",
    rom_sha1="d52c2f85f56c963ff5e48a096afc61d3c8a71c11",
    action_keys=(6, 5, 9, 8, 7),
    score_fn=_score,
    terminated_fn=lambda state: state.V[LIVES] == 0,
    lives_fn=lambda state: state.V[LIVES].astype("int32"),
    startup=((0, 30), (key_mask(6), 3), (0, 1)),
    max_episode_steps=4500,
    category="reaction",
    description="Play random microgames (dig with key 6, drop a hat with 6, repeat a dance with "
                "5/9/8/7); reward +1 per round reached; a lost microgame costs one of 4 lives and "
                "the game ends with none left.",
),)
