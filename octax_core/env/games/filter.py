"""Filter: catch the drops that fall from a pipe at the top of the screen with a paddle.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the pipe, one falling drop, the paddle near the
bottom, the lives left (top left) and the drops caught (top right).

### Actions
0: no-op, 1: key 4 (paddle left), 2: key 6 (paddle right).

### Reward
Change of V14, the drops caught: +1 per drop.

### Termination
V13 (lives, 7 at the start) reaches 0, or V14 reaches 99; in both cases the ROM halts in a
jump-to-self (pc 0x25C). The paper ends on V13 only, but a player that catches 99 drops halts
the game with lives left.

Quirks "chip8": an original CHIP-8 program (community database: originalChip8); the quirks
that differ do not change its logic (no shift, BNNN or 8XY1-3; I after FX65 is never read), so
the profile only sets the VIP's display-wait pacing. Timers: real 60 Hz; the game loop waits
one frame of delay timer per drop move. Start-up: 12 frames (octax: none; V13 is 0 for the
first instructions), until the pipe, the counters and the paddle are drawn; each drop's column
is drawn from the reset key. Episodes are cut at 4,500 steps (5 minutes).
"""


from octax_core.env.games.spec import GameSpec, register_value


SPECS = (GameSpec(
    id="Filter",
    title="Filter",
    rom_file="Filter.ch8",
    rom_sha1="ae71a7b081a947f1760cdc147759803aea45e751",
    action_keys=(4, 6),
    score_fn=lambda state: register_value(state, 14),
    terminated_fn=lambda state: (state.V[13] == 0) | (state.V[14] == 99),
    lives_fn=lambda state: register_value(state, 13),
    startup=((0, 12),),
    quirks="chip8",
    max_episode_steps=4500,
    category="timing",
    description="Move the paddle (keys 4 left, 6 right) under the falling drops; reward +1 per drop "
                "caught; the game ends when the 7 lives are gone or 99 drops are caught.",
),)
