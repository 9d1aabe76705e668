"""Ghost Escape (Octojam 3, archive "ghostEscape"): stack falling columns by pressing X in time.

### Observation
The screen, uint8 (frames_per_step, 32, 64): one column of the 64 per placement, left to right;
the current column's segment (its two end pixels) falls one row per loop, and the last placed
segment is drawn in full beside it.

### Actions
0: no-op, 1: key 0 (X: drop the segment here). The ROM reads no other key. A press keeps only the
rows the new segment shares with the last one (`ntw` vA becomes the next width `wid` v5), moves
to the next column (`col` v3) and starts the next segment at the top.

### Reward
+1 for every step the game goes on (`survival_reward`). The ROM keeps no score it could hand back:
the placed-column count `col` (v3) is reset by `main` in the same loop that loses, and no register
or memory survives the restart, so a per-placement reward would be taken back at the end. Survival
tracks placements: an unplaced segment reaches the bottom in about 14 steps.

### Termination
Every loss jumps back to `main` (0x200): the segment reaches the bottom (`v6 == 32`), a press on
its first row, or a press with no overlap or a width over 10. The episode ends while `main`
redraws the first two columns: pc in `main` before the play loop (0x200..0x215), or in
`startline` (0x276..0x285) with `row` (v4) not 0 (in play, `startline` always runs with `row` 0).
That stretch takes about 90 instructions, 3 steps at this speed, so a step always ends inside it.

Options from the archive: tickrate 7, no quirks, real timers (the loop paces itself at one row per
3 frames with the delay timer, and waits 8 frames after a placement). The ROM has no title: start-up
is 20 frames of `main` drawing the first columns. It draws no random numbers, so every episode is
the same for the same actions. Episodes are cut at 4,500 steps (5 minutes).
"""

from octax_core.env.games.archive._program import archive_spec

MAIN_INIT = (0x200, 0x216)  # `main` up to the play loop
STARTLINE = (0x276, 0x286)  # `startline` up to `dot`
ROW = 4  # `:alias row v4`


def _restarting(state):
    in_main = (state.pc >= MAIN_INIT[0]) & (state.pc < MAIN_INIT[1])
    in_startline = (state.pc >= STARTLINE[0]) & (state.pc < STARTLINE[1])
    return in_main | (in_startline & (state.V[ROW] != 0))


SPECS = (archive_spec(
    "ghostEscape",
    id="GhostEscape",
    rom_sha1="1e3be162480380b6276d0848e1c71576b4c041f2",
    action_keys=(0,),
    score_fn=lambda state: state.V[0] * 0,
    survival_reward=1.0,
    terminated_fn=_restarting,
    startup=((0, 20),),
    max_episode_steps=4500,
    category="timing",
    description="Press key 0 (X) while the falling segment overlaps the last placed one to fix it "
                "and move to the next column; only the overlap carries on. Reward +1 per step "
                "survived; the episode ends when a segment reaches the bottom or a press misses.",
),)
