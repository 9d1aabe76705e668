"""Brix (Andreas Gustafsson, 1990): Breakout; bounce the ball off a paddle into 96 bricks.

### Observation
The screen, uint8 (frames_per_step, 32, 64): 6 rows of 16 bricks, the paddle at the bottom,
the lives left and the score on top.

### Actions
0: no-op, 1: key 4 (paddle left), 2: key 6 (paddle right).

### Reward
Change of V5, the bricks destroyed: +1 per brick.

### Termination
The paper's rule, V14 (lives, 5 at the start) equals 4, or V5 reaches 96: all bricks gone, the
ROM's win (it halts in a jump-to-self at pc 0x2DE), kept because V14 == 4 alone cannot see it
(a won episode still has all 5 balls). An episode is thus one ball: it ends on the step the
first ball is lost.

Where the ROM and the paper disagree: the paper calls V14 == 4 "no more lives", but the ROM
gives 5 balls and plays on after the first is lost, down to V14 == 0, where it halts (pc 0x2DE).
The paper's rule therefore ends at the first lost ball, with 4 lives left (`lives_fn` still reads
V14, so the final info shows 4). For the whole 5-ball game use instead
`terminated_fn=lambda s: (s.V[14] == 0) | (s.V[5] == 96)` in a `dataclasses.replace` of this
spec, passed to `make`.

Quirks "chip8": an original CHIP-8 program (community database: originalChip8); the quirks
that differ do not change its logic (no shift or BNNN; VF after 8XY2/8XY3 and I after FX65 are
never read), so the profile only sets the VIP's display-wait pacing: one brick per frame while
the wall is drawn, four frames per ball move. Timers: real 60 Hz; the game waits 64 frames (16
steps) before each serve. Start-up: 160 frames (octax: 500 instructions = 46), the wall drawn
and 5 frames before the first serve, whose column is drawn from the reset key. Episodes are cut
at 4,500 steps (5 minutes); one ball lasts 32-128 steps with the paddle left still or held to one
side, 33-303 under random play (measured).
"""


from octax_core.env.games.spec import GameSpec, register_value


SPECS = (GameSpec(
    id="Brix",
    title="Brix",
    rom_file="Brix [Andreas Gustafsson, 1990].ch8",
    rom_sha1="f13766c14aeb02ad8d4d103cb5eadd282d20cddc",
    action_keys=(4, 6),
    score_fn=lambda state: register_value(state, 5),
    terminated_fn=lambda state: (state.V[14] == 4) | (state.V[5] == 96),  # the paper's rule, plus the win
    lives_fn=lambda state: register_value(state, 14),
    startup=((0, 160),),
    quirks="chip8",
    max_episode_steps=4500,
    category="timing",
    description="Move the paddle (keys 4 left, 6 right) to bounce the ball into the bricks; reward "
                "+1 per brick; the episode ends when the first ball is lost (V14 == 4, the paper's "
                "rule) or all 96 bricks are gone.",
),)
