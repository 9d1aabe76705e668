"""Civiliz8n (Octojam 2, archive "civiliz8n"): grow a tiny civilization of hex tiles in 10 turns.

### Observation
The screen, uint8 (frames_per_step, 64, 128), XO-CHIP pixel codes 0..3 (plane 1 + 2 x plane 2):
a hex map in hires with random trees, the placed tiles, the three tile choices on the left (keys
1-3), the six direction arrows around the last tile, the score and the turns used.

### Actions
0: no-op; 1-3: keys 1, 2, 3 (select one of the three offered tiles); 4-9: keys 4, 5, 6, 7, 8, 9
(place the selected tile on a neighbour of the last one: `keyToIndex` maps them to the six hex
directions). Input is FX0A (`keyInput`): a key counts once, when it is released, so a key held
for several steps is one press. Left out: key D (restart, on the score screen) and key C
(Hammurabi mode, chosen on the title).

### Reward
The points each turn scores: the change of `score` (RAM 0x204), which `updateScore` adds the
turn's `scoreAdd` to (huts +1 and a bonus hut, gardens +2 or +4 in a group of 3, meeting circles
+1 and +5 when surrounded, shrines +5 when far from others, temples +1 per different neighbour,
foresters +1 per tree cut).

### Termination
The game's end: after the 10th turn, or earlier when the last tile is trapped, `gameOver` sets
`gameState` (VD, `:alias gameState vd`) to `state_showingScore` (5) and flashes the score until
key D restarts, which no action holds.

Options from the archive: XO-CHIP, tickrate 100, Octo's default quirks, its own four colours.
The source does not reassemble byte for byte with our assembler (164 bytes differ: older Octo
used VE, not VF, as the temporary of its comparison pseudo-ops), but every label is at the same
address. Start-up: 20 frames (the title drawn), then key 1 held 2 frames (the 10-turn game; its
FX0A completes when the first env step releases the key), so `setupGame`'s random trees and the
first tile choices are drawn from each episode's reset key. Episodes are cut at 1,000 steps
(10 turns need 20 or more key presses).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import key_mask, ram_value

SCORE = 0x204  # `score`
GAME_STATE, SHOWING_SCORE = 13, 5  # VD, `state_showingScore`

SPECS = (archive_spec(
    "civiliz8n",
    id="Civiliz8n",
    rom_sha1="76a770000b314659ac792e17724b783a464ab67e",
    action_keys=(1, 2, 3, 4, 5, 6, 7, 8, 9),
    score_fn=lambda state: ram_value(state, SCORE),
    terminated_fn=lambda state: state.V[GAME_STATE] == SHOWING_SCORE,
    startup=((0, 20), (key_mask(1), 2)),
    max_episode_steps=1000,
    category="planning",
    description="Each turn select one of three tiles (keys 1-3) and place it beside the last one "
                "(keys 4-9, six hex directions); reward: the points the tile scores; the game ends "
                "after 10 turns or when the last tile is trapped.",
),)
