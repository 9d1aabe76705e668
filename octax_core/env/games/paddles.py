"""Paddles (unknown author; in the octax ROM set): two-player vertical pong, one paddle on top and
one at the bottom, two bars in the middle of the court.

A two-player game here (`solo=False`: `octax_core.make_multi("Paddles")`): its title waits for key
F (one player: "C" "P", the bottom paddle against a computer top paddle) or key E (two players:
"A" "B"); the start-up picks E. The one-player mode is not offered as a one-player env, so that the
octax suite's one-player list stays the paper's titles.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the top paddle (row 1, 8 pixels wide, x in VA), the
bottom paddle (row 30, x in VB), the ball (one pixel at (VC, VD)), two 8-pixel bars on row 16
(x 8 and 56, or 48 and 56: `random 2`, drawn after the start-up from the episode's reset key), a
left border and the scores (hex digits: A's at the top left, B's at the bottom left, with the
letters A and B between them). In `make_multi` the last plane is the player plane.

### Actions
Seat 0, player A (top paddle): 0: no-op, 1: key 4 (left), 2: key 6 (right). Seat 1, player B
(bottom paddle): 0: no-op, 1: key 7 (left), 2: key 9 (right). The two-player loop (0x2C0) reads
the four keys every pass and moves a paddle 2 pixels a pass, within x 8..56. The keys are the
ROM's: both players press the one keypad at once (simultaneous: `current_player` -1).

### Reward
Zero-sum: each seat's score is its points minus the other's, the change is the reward (+1 for a
point won, -1 for a point lost). The ROM keeps A's points in V8 (raised when the ball reaches row
31, past B's paddle: 0x280) and B's in V9 (the ball at row 0, past A's: 0x266); they are only
drawn elsewhere (`i := hex v8`), never reused.

### Termination
Either side reaches 9 points: the ROM jumps to 0x41C, a jump to itself, and stands still.

Quirks "chip8" (no shift, BNNN or FX55/FX65; VF is read only after DXYN): the VIP's display-wait
pacing, one sprite a frame; a pass of the game loop draws six (the ball and both paddles undrawn
and drawn), so the ball moves one pixel every 6 frames (1.5 steps). Timers: real 60 Hz (only the
buzzer). A paddle hit sends the ball off at random 45 degrees (`random 1`), a bar or wall bounces
it back. Start-up: 20 frames (the court drawn, the title's key loop at 0x21A), then key E held 1
frame: two players; the court is redrawn after it, from the episode's reset key. Episodes are cut
at 4,500 steps (5 minutes).

Scripted policy (`Seats.scripted_policy`): moves its paddle under the ball's column (VC).
Measured (`make_multi`, frames_per_step 4, 64 envs x 4,500 steps with autoreset, the episodes
that finished): random vs random, seat 0 mean return +0.38 (wins 0.57), 1,216 steps a game;
scripted (seat 0) vs random wins every game, mean +8.96 (1,394 steps); random vs scripted (seat 1)
loses every game, mean -9.00; scripted vs scripted rallies on: no game of 64 ended in 4,500 steps.
"""

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec, Seats, key_mask

POINTS = (8, 9)  # V8: player A (top paddle), V9: player B (bottom paddle)
PADDLE_X = (0xA, 0xB)  # VA top, VB bottom
BALL_X = 0xC
GAME_OVER_PC = 0x41C  # `jump 0x41C`
POINTS_TO_WIN = 9
LEFT, RIGHT = 1, 2
PADDLE_WIDTH = 8


def _points(state):
    return jnp.stack([state.V[POINTS[0]], state.V[POINTS[1]]]).astype(jnp.int32)


def _lead(state):
    points = _points(state)
    return jnp.stack([points[0] - points[1], points[1] - points[0]])


def _over(state):
    return (_points(state).max() >= POINTS_TO_WIN) | (state.pc == GAME_OVER_PC)


def scripted_policy(state, seat: int):
    """Keep the ball's column over the paddle's middle two pixels."""
    paddle = state.V[PADDLE_X[seat]].astype(jnp.int32)
    ball = state.V[BALL_X].astype(jnp.int32)
    return jnp.where(ball < paddle + 3, LEFT, jnp.where(ball > paddle + 4, RIGHT, 0)).astype(jnp.int32)


SPECS = (GameSpec(
    id="Paddles",
    title="Paddles (2 players)",
    rom_file="Paddles (unknown author)(xxxx).ch8",
    rom_sha1="a18f1e3897416180b32e47ddc82cba9aca2c8d52",
    action_keys=(4, 6),
    score_fn=lambda state: _lead(state)[0],
    terminated_fn=_over,
    startup=((0, 20), (key_mask(0xE), 1)),
    quirks="chip8",
    max_episode_steps=4500,
    solo=False,
    seats=Seats(
        action_keys=((4, 6), (7, 9)),
        score_fn=_lead,
        zero_sum=True,
        names=("A (top paddle)", "B (bottom paddle)"),
        scripted_policy=scripted_policy,
    ),
    category="timing",
    description="Two players move the top paddle (keys 4/6) and the bottom paddle (keys 7/9) to "
                "return a ball past two bars; reward +1 per point won and -1 per point lost "
                "(zero-sum); the game ends when either side reaches 9 points.",
),)
