"""Vertical Brix (Paul Robson, 1996): Breakout turned sideways; the paddle moves up and down.

### Observation
The screen, uint8 (frames_per_step, 32, 64): a border, 7 columns of 10 bricks on the right,
the paddle on the left, the ball, the score and the lives left on top.

### Actions
0: no-op, 1: key 1 (paddle up), 2: key 4 (paddle down).

### Reward
Change of V8, the bricks destroyed: +1 per brick (a cleared wall is redrawn and play goes on).

### Termination
V7 (lives, 3 at the start) reaches 0. V7 is also 0 on the title screen, which the start-up
leaves.

Quirks "chip8": an original CHIP-8 program (community database: originalChip8); the quirks
that differ do not change its logic (no shift, BNNN or 8XY1-3; I after FX65 is never read), so
the profile only sets the VIP's display-wait pacing. Timers: real 60 Hz; the game pauses 120
frames (30 steps) after a lost ball. Start-up, as in octax (key 7 held for 1,000 instructions,
then released): key 7 held for 250 frames, which leaves the title screen and reaches the FX0A
before the first serve, then released for 1 frame, which serves; the agent never needs key 7.
The ball's first row is the ROM's only random draw and happens during the start-up, so every
episode starts the same (use `noop_max` to vary the start). Episodes are cut at 4,500 steps (5
minutes).
"""


from octax_core.env.games.spec import GameSpec, key_mask, register_value


SPECS = (GameSpec(
    id="VerticalBrix",
    title="Vertical Brix",
    rom_file="Vertical Brix [Paul Robson, 1996].ch8",
    rom_sha1="da710f631f8e35534d0b9170bcf892a60f49c43d",
    action_keys=(1, 4),
    score_fn=lambda state: register_value(state, 8),
    terminated_fn=lambda state: state.V[7] == 0,
    lives_fn=lambda state: register_value(state, 7),
    startup=((key_mask(7), 250), (0, 1)),
    quirks="chip8",
    max_episode_steps=4500,
    category="timing",
    description="Move the paddle (keys 1 up, 4 down) to bounce the ball into the bricks; reward +1 "
                "per brick; the game ends when the 3 balls are lost.",
),)
