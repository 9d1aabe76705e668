"""Cave Explorer (2014, archive "caveexplorer"): explore a cave, solve the block puzzles that lead out.

### Observation
The screen, uint8 (frames_per_step, 32, 64). On the overworld: one of 16 boards, a 16x8 maze of
4x4-pixel paths among rocks, the explorer (a 2x2 dot) and, where a board's secret is not found
yet, its target. In a block puzzle: an 8x4 side view of 8x8 tiles (floor,
roof, blocks, the exit door and the explorer facing left or right). Text pages between.

### Actions
0: no-op, 1: key 7 (Octo's A: west / walk left), 2: key 9 (D: east / walk right), 3: key 5
(W: north), 4: key 8 (S: south), 5: key 6 (E: in a puzzle, pick up or set down a block). Every
input is an FX0A, so a key counts when it is released: one move per press. Key 5 (or any key)
also turns the pages of text. (Key 4, Octo's Q, which restarts the puzzle in play, is not offered;
in a puzzle a turn costs one press, a step a second.)

### Reward
+1 per secret found and +1 per block puzzle solved. Secrets: `special-complete` (0x278, one byte
per board, set to 1 by `do-special` as the explorer steps on the board's target: a puzzle's
entrance, a gate opened by a rumble, a hint or a joke; 16 in all). Puzzles: `puzzle-finished-count`
(0xAAA), which `block-puzzle` increments as a puzzle is won; `check-puzzles` adds one more when it
reaches 7 (to show the "return to where this all began" page and open the way to board 0's exit
puzzle), so from 8 on one less is counted. At most 16 + 8 = 24, both only ever grow.

### Termination
The way out: winning the eighth puzzle (`puzzle-7`, level 7, entered at board 0's target, which
is reachable only after the other seven are won). `puzzle-7` then shows the ending (0xE3D..0xE52:
text, a key, the bus picture and `loop again` forever); the pc there, or in a routine called from
there, is the end. There is no way to lose.

Options from the archive: tickrate 20, Octo's default quirks, its colours. Start-up: 700 frames
(the intro: two bitmaps and three captioned pauses of 128 frames), key 5 held 2 frames for the
title's FX0A (completed by the release), 100 frames (the first board drawn) so that every episode
starts at the overworld's first `v2 := key` (0xECD). The game draws no random numbers that
matter (`random` only picks the rocks' look), so only the policy varies it. The game is long
(the tests' walkthrough, found by search, is 662 key presses and ends at step 2,826): episodes
are cut at 9,000 steps (10 minutes).
"""

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, ram_value

SPECIAL_COMPLETE = 0x278  # `special-complete`: one byte per board, 1 once its secret is found
BOARDS = 16
PUZZLE_FINISHED_COUNT = 0xAAA  # `puzzle-finished-count`: puzzles won, plus one from 7 on
THE_END = (0xE3D, 0xE53)  # `puzzle-7` after its `block-puzzle`: the ending


def _progress(state):
    secrets = sum(ram_value(state, SPECIAL_COMPLETE + board) for board in range(BOARDS))
    count = ram_value(state, PUZZLE_FINISHED_COUNT)
    return secrets + count - (count >= 8)


SPECS = (archive_spec(
    "caveexplorer",
    id="CaveExplorer",
    rom_sha1="400dbd1aa2b79b9b8546bc615bfb735c1bd1d268",
    action_keys=(7, 9, 5, 8, 6),
    score_fn=_progress,
    terminated_fn=lambda state: in_routine(state, *THE_END),
    startup=((0, 700), (key_mask(5), 2), (0, 100)),
    max_episode_steps=9000,
    category="navigation",
    description="Explore the cave's 16 boards (keys 7/9/5/8: west, east, north, south, one move a "
                "press) and solve its block puzzles (7/9 walk and climb, 6 picks up and sets down "
                "blocks); reward +1 per secret found and +1 per puzzle solved; the game ends when "
                "the eighth puzzle, the way out, is solved.",
),)
