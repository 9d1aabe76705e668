"""Duel (octax-gym, 2026): a two-player volley, paddle against paddle. Our own game.

The source is `roms/duel.8o` (Octo), built into the committed `roms/duel.ch8` by `make roms`;
the ROM store finds it in the project's `roms/` folder.

Simultaneous and symmetric: the two sides are each other's left/right mirror image and play by
the same rules; both move in every step. Two players: `octax_core.make_multi("Duel")`. One
player: `make("Duel")` is player 1 against an idle player 2 (a paddle standing in the middle).

### Observation
The screen, uint8 (frames_per_step, 32, 64): the two scores (one digit each) at the top, player
1's paddle (1x6) at x = 2, player 2's at x = 61, the ball (2x2). `make_multi` adds the player
plane (0 for player 1, `obs_scale` for player 2).

### Actions (per seat)
0: no-op, 1: paddle up, 2: paddle down; 1 pixel a move. Player 1 (left): keys 1 and 4; player
2 (right): keys C and D.

### Reward
Two players: zero-sum; a seat's score is its points minus the other's (V5 - V6 for player 1, V6
- V5 for player 2), so a point is +1 to its winner and -1 to the other. One player: V5, player
1's points (+1 per point), with V6 as lives lost (`lives_fn` 7 - V6).

### Termination
VE (0 while playing) becomes 1 when either side reaches 7 points; the ROM then loops on itself
with the final score on the screen.

### Numbers
Measured with `make_multi("Duel")` defaults, 256 episodes each (returns of player 1; player 2's
is the negative): uniform random against uniform random: return +0.36 +- 3.47, length 544 +- 142
steps, player 1 winning 56% (again with 1,024 other episodes: -0.22 +- 3.41, 547 +- 138 steps,
47%: the sides are even). The scripted policy (`Seats.scripted_policy`: wait in the middle
while the ball goes away, then move the paddle's middle to the row where the ball will cross
its column, folding its bounces) against uniform random wins every episode 7-0 from either
seat, in 661 +- 247 steps. Two scripted players never miss: no point in 4,500 steps.

Quirks "chip8": written for it; no shift, BNNN or 8XY1-3, and I is set before every FX65, so
every profile plays it the same except for the pace (display wait ends a frame at each sprite:
about 6 frames a ball move, 2 more per paddle moved). Both players' keys are read in the first 8 instructions of one
frame, opened by the ball's erasure (under display wait a sprite ends its frame), so neither
side sees a new action sooner. Timers: real 60 Hz; the delay timer times the pause before the
first serve (40 frames) and the 20 frames a serve waits at the centre, the paddles moving. Start-up:
20 frames, inside the first pause, so the first serve (its row, side and climb) is drawn from
each episode's reset key. Episodes are cut at 4,500 steps (5 minutes).
"""

import dataclasses
import functools

import jax
import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec, Seats, register_value

PAD1, PAD2, SCORE1, SCORE2, BALL_X, BALL_Y, BALL_DX, BALL_DY, GAME_OVER = 3, 4, 5, 6, 7, 8, 9, 10, 14
WIN = 7
PADDLE_X = (2, 61)
HIT_X = (3, 59)  # the ball's x beside each paddle
BALL_SPEED = {0: 2, 1: 6}  # pixels a move across, by version (roms/duel.8o, roms/duel_v1.8o)


def _scores(state):
    """(V5 - V6, V6 - V5): a point is +1 to its winner and -1 to the other."""
    points = jnp.stack([register_value(state, SCORE1), register_value(state, SCORE2)])
    return points - points[::-1]


def _crossing_row(state, seat: int, speed: int = 2):
    """The row the ball's top will have when it reaches `seat`'s paddle column (folding its bounces
    off rows 0 and 30), or where it is now if it moves away from that side. `speed`: the ball's
    pixels a move across; the move that would pass the paddle's face stops there (v1), so the
    moves left are the distance over `speed`, rounded up (exact in v0, whose x is always odd)."""
    x = register_value(state, BALL_X)
    y = register_value(state, BALL_Y)
    dx = jnp.where(state.V[BALL_DX] == speed, speed, -speed)
    dy = jnp.where(state.V[BALL_DY] >= 128, register_value(state, BALL_DY) - 256, register_value(state, BALL_DY))
    toward = dx == (-speed if seat == 0 else speed)
    moves = (jnp.abs(HIT_X[seat] - x) + speed - 1) // speed
    unfolded = jnp.mod(y + dy * moves, 60)  # the bounces fold y into 0..30: a period of 60
    folded = jnp.where(unfolded > 30, 60 - unfolded, unfolded)
    return jnp.where(toward, folded, 14)


def scripted_policy(state, seat: int, speed: int = 2) -> jax.Array:
    """Move the paddle's middle (rows p+2, p+3) to where the ball will cross its column."""
    paddle = register_value(state, PAD1 if seat == 0 else PAD2)
    target = _crossing_row(state, seat, speed) + 1 - 3  # the ball's rows y, y+1 on the paddle's middle
    return jnp.where(target < paddle, 1, jnp.where(target > paddle, 2, 0)).astype(jnp.int32)


SEATS = Seats(
    action_keys=((0x1, 0x4), (0xC, 0xD)),  # up, down: player 1 (left) 1/4, player 2 (right) C/D
    score_fn=_scores,
    zero_sum=True,
    names=("left paddle", "right paddle"),
    scripted_policy=scripted_policy,
)

SUITE = "ours"
DUEL = GameSpec(
    id="Duel",
    title="Duel (two-player volley, first to 7)",
    rom_file="duel.ch8",
    rom_sha1="204f836197b79bb6303d406b28141a3264b6b355",
    action_keys=(0x1, 0x4),
    score_fn=lambda state: register_value(state, SCORE1),
    terminated_fn=lambda state: state.V[GAME_OVER] == 1,
    lives_fn=lambda state: WIN - register_value(state, SCORE2),
    startup=((0, 20),),
    quirks="chip8",
    max_episode_steps=4500,
    seats=SEATS,
    category="timing",
    description="Two paddles, one ball: move your paddle (player 1 left: keys 1 up, 4 down; player 2 "
                "right: C up, D down) to send the ball back; a ball that gets past a paddle is a "
                "point for the other side; first to 7 points ends the game (VE == 1). Two players: "
                "zero-sum rewards, +1/-1 per point; one player (against an idle right paddle): +1 "
                "per point.",
)
# Version 1 (roms/duel_v1.8o, where the changes and their reasons are written): the ball moves 6
# pixels a move across instead of 2 and is drawn in every frame, so a paddle cannot always get
# there in time and the scripted player, the same reader of the ball, concedes points to itself.
# A two-player game only (not solo): it exists for the ladder (docs/multiplayer.md); the
# one-player view is a seat against an opponent (`opponent=`).
DUEL_V1 = dataclasses.replace(
    DUEL,
    id="Duel-v1",
    version=1,
    title="Duel v1 (two-player volley, a fast ball, first to 7)",
    rom_file="duel_v1.ch8",
    rom_sha1="542fb42490a028bb58aadb1631ed1042467dfc6d",
    solo=False,
    seats=dataclasses.replace(SEATS, scripted_policy=functools.partial(scripted_policy, speed=BALL_SPEED[1])),
    description="Duel with a ball three times as fast (6 pixels a move across) and drawn in every frame: a "
                "paddle cannot always reach the ball in time, so even the scripted players concede points. Keys, "
                "bounces, serve, scores and the end as Duel's (player 1 left: keys 1 up, 4 down; player 2 right: "
                "C up, D down; first to 7 points ends the game, VE == 1); zero-sum rewards, +1/-1 per point. Two "
                "players only: the one-agent view is a seat against an opponent.",
)
SPECS = (DUEL, DUEL_V1)
