"""Piper (Global Game Jam 2017, archive "piper"): a little bird collects goodies and hides from waves.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the bird, the goodies (star, dollar, shell, swirls),
the score (3 digits, bottom right), and the waves that sweep the beach from time to time.

### Actions
0: no-op, 1: key 6 (Octo's E: hide; the bird ducks out of the waves' way and stays still),
2: key 5 (W: up), 3: key 8 (S: down), 4: key 7 (A: left), 5: key 9 (D: right).

### Reward
+1 per goody collected: the change of `score` (VB, `:alias score vb`), which `inc-score` adds
to (it also writes the BCD the screen shows). The register is 8 bits: a score past 255 would
wrap, far beyond what an episode reaches.

### Termination
A wave reaching the bird while it is not hidden and below the wave's line (`wave-collision`):
`game-over` (0x5F0..0x5FF) waits 40 frames, draws the score and the bird, then `draw-bird-cry`
animates its tears forever; any step that ends there, or in a subroutine `game-over` called,
ends the episode.

Options from the archive: CHIP-8, tickrate 200, Octo's default quirks, its colours. The source
does not reassemble byte for byte (52 bytes differ: comparison pseudo-ops' temporary register),
every label at the same address. A move every 3 frames (`delay-loop`); the time between waves is
`random 0xFF` frames, at least 200. Start-up: 10 frames (the intro drawn), key 5 held 2 frames for
the intro's FX0A, which completes when the first env step releases it, so the goodies, the bird's
spawn point and the waves are all drawn from each episode's reset key. Episodes are cut at 4,500
steps (5 minutes).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, register_value

SCORE = 11  # VB
GAME_OVER = (0x5F0, 0x600)  # `game-over` (its calls, `draw-bird-cry` among them, run from here)

SPECS = (archive_spec(
    "piper",
    id="Piper",
    rom_sha1="7da3eba52a8d8025ddf14ee40d28f151585529a0",
    action_keys=(6, 5, 8, 7, 9),
    score_fn=lambda state: register_value(state, SCORE),
    terminated_fn=lambda state: in_routine(state, *GAME_OVER),
    startup=((0, 10), (key_mask(5), 2)),
    max_episode_steps=4500,
    category="navigation",
    description="Fly the bird (keys 5/8/7/9) to collect goodies and hide (key 6) when a wave comes; "
                "reward +1 per goody; the game ends when a wave catches the bird.",
),)
