"""Masquer8 (Octojam 2, archive "masquer8"): camouflage Cammy the cuttlefish to match the sea floor.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the level's pattern (2 to 3 overlaid stripe, line or
check patterns) around the cuttlefish, the cuttlefish wearing the patterns toggled so far, and a
HUD in the bottom-right corner (the moves left before the next check, the shark's distance).

### Actions
0: no-op, 1: key F (Octo V: "blend in", check the match now), 2..5: keys 1 2 3 C (vertical
lines), 6..9: keys 4 5 6 D (horizontal lines, unlocked after level 2), 10..16: keys 7 8 9 E A 0 B
(patterns, unlocked after level 4). Each pattern key toggles (XORs) one pattern on the body; keys
not unlocked yet count as a wasted move. Every key is read by one FX0A (`v-key := key`, 0x264),
so a move is a press then a release. Key A on the title screen starts the endless random mode,
which the start-up never takes.

### Reward
+1 per level solved: the change of `:alias levelnum ve`, which `level-complete` (0x2D4)
increments; ve is only reused as the loading bar's y before the game starts, so it never jumps.
The ten story levels give at most 10.

### Termination
The shark catches Cammy: after 8 failed checks (`:alias Checks vb` reaches `checkmax`) or ten V
presses in a row (`mash-reset`), the ROM jumps to `game-over` (0x334..0x373), whose text screens
wait on FX0A; the episode ends while that routine or a helper it called runs.

Options from the archive: tickrate 15, Octo's default quirks. The shipped ROM is a slightly later
build than src/masquer8.8o (two bytes longer; key 2, not key 3, solves level 1), so the addresses
above were read from its disassembly; the level code and data are unchanged. A check comes
every 9 moves, or at once with V; a failed check brings the shark closer. Start-up: 640 frames of
the loading screen (the ROM builds its pattern tables), then key 1 on the "press key" title
(new game from level 1) and the three story screens, the last one left held, so the first step's
release starts level 1. Story levels are fixed, so the game draws no random numbers (only the
endless mode does) and episodes differ only by the agent's play. Episodes are cut at 4,500 steps.
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, register_value

LEVELNUM = 0xE  # `:alias levelnum ve`
GAME_OVER = (0x334, 0x374)  # `game-over`, up to `draw-shark` (shipped ROM)
STORY_SCREENS = tuple(step for _ in range(3) for step in ((key_mask(1), 2), (0, 150)))

SPECS = (archive_spec(
    "masquer8",
    id="Masquer8",
    rom_sha1="fb48e162c7f2e8853909acc5534b55fb55030f9f",
    action_keys=(0xF, 1, 2, 3, 0xC, 4, 5, 6, 0xD, 7, 8, 9, 0xE, 0xA, 0, 0xB),
    score_fn=lambda state: register_value(state, LEVELNUM),
    terminated_fn=lambda state: in_routine(state, *GAME_OVER),
    startup=((0, 640),) + STORY_SCREENS + ((key_mask(1), 2),),
    max_episode_steps=4500,
    category="planning",
    description="Toggle patterns on the cuttlefish (keys 1 2 3 C, later 4 5 6 D and 7 8 9 E A 0 B) "
                "until they match the surroundings, then blend in with key F; reward +1 per level "
                "solved; the game ends when the shark arrives after 8 failed checks.",
),)
