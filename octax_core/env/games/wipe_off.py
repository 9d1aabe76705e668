"""Wipe Off (Joseph Weisbecker, COSMAC VIP): bounce a ball off a paddle to wipe out spots.

### Observation
The screen, uint8 (frames_per_step, 32, 64): 112 spots in 7 rows, the paddle at the bottom,
the ball; the score is shown only once the game is over.

### Actions
0: no-op, 1: key 4 (paddle left), 2: key 6 (paddle right).

### Reward
Change of V6, the spots wiped out: +1 per spot.

### Termination
V7 (balls left) reaches 0, or V6 reaches 112 (every spot gone); in both cases the ROM shows the
score and halts. The paper ends on V7 only, but a cleared board halts with V7 > 0. The ROM
serves 15 balls (V7 = 16, less one before the first serve), not the 20 of the VIP manual.
Before every serve it waits (FX0A) for a key to be pressed and released, so a policy that never
changes its action never serves.

Quirks "chip8": a COSMAC VIP program (community database: originalChip8); the quirks that
differ do not change its logic (no shift or BNNN; VF after 8XY2 and I after FX65 are never
read), so the profile only sets the VIP's display-wait pacing. Timers: real 60 Hz (only the
sound timer is used). Start-up: 60 frames (octax: 500 instructions = 46), until the spots are
drawn and the ROM waits for the first serve; V7 is 0 until then. Each serve's direction is
drawn from the reset key. Episodes are cut at 4,500 steps (5 minutes).
"""


from octax_core.env.games.spec import GameSpec, register_value


SPECS = (GameSpec(
    id="WipeOff",
    title="Wipe Off",
    rom_file="Wipe Off [Joseph Weisbecker].ch8",
    rom_sha1="d666688a8fce468a7d88b536bc1ef5f35ba12031",
    action_keys=(4, 6),
    score_fn=lambda state: register_value(state, 6),
    terminated_fn=lambda state: (state.V[7] == 0) | (state.V[6] == 112),
    lives_fn=lambda state: register_value(state, 7),
    startup=((0, 60),),
    quirks="chip8",
    max_episode_steps=4500,
    category="timing",
    description="Serve (press and release a key), then move the paddle (keys 4 left, 6 right) to "
                "bounce the ball into the spots; reward +1 per spot; the game ends after 15 balls "
                "or when all 112 spots are gone.",
),)
