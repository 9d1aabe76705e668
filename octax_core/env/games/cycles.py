"""Cycles (octax-gym, 2026): a two-player light-cycle duel, in three levels. Our own game.

The source is `roms/cycles.8o` (Octo), built into the committed `roms/cycles.ch8` by `make roms`;
the ROM store finds it in the project's `roms/` folder.

Simultaneous and symmetric: both cycles move one cell every move, on halves of the arena that
mirror each other (left/right), by the same rules. Two players: `octax_core.make_multi("Cycles")`.
One player: `make("Cycles")` is player 1 against an idle player 2, who runs straight on.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the arena, 32x16 cells of 2x2 pixels whose outer
ring is a wall, the obstacles (2x2 cells), and the two cycles' walls of light; between rounds,
the two scores. `make_multi` adds the player plane (0 for player 1, `obs_scale` for player 2).

### Actions (per seat)
0: no-op (straight on), 1: up, 2: down, 3: left, 4: right; a key for the way back is ignored.
Player 1 (starts left, heading right): keys 5, 8, 7, 9; player 2 (starts right, heading left):
keys C, D, E, F.

### Reward
Two players: zero-sum; a seat's score is its rounds won minus the other's (V5 - V6 for player 1,
V6 - V5 for player 2), so a round is +1 to its winner and -1 to the other; a drawn round (both
crash in one move, or meet in one cell) gives nothing. One player: V5, player 1's rounds (+1
each), with V6 as lives lost (`lives_fn` 5 - V6).

### Termination
VE (0 while playing) becomes 1 when either side has won 5 rounds; the ROM then shows the final
score and loops on itself.

### Levels
One ROM serves the three levels, chosen on its start screen by key 1, 2 or 3: 0, 3 and 6 pairs
of 2x2-cell obstacles at random places (each pair mirrored left/right). `Cycles1`..`Cycles3`
press that key at start-up; `Cycles` is the middle level, `Cycles2`.
Measured with `make_multi` defaults, 256 episodes each (returns of player 1; player 2's is the
negative), levels 1, 2, 3: uniform random against uniform random: return +0.18 +- 2.75, +0.05
+- 2.75, +0.08 +- 2.72, length 291, 291 and 310 steps (a random cycle soon runs into a wall or
its own trail, obstacles or none; player 1 wins 54%, 50%, 54%). The scripted policy
(`Seats.scripted_policy`: of the headings open to it, the one with the longest free run ahead,
up to 12 cells) against uniform random wins every episode, 5-0 from either seat (once 5-1),
in 216-231 steps. Scripted against scripted: rounds of hundreds of steps, most matches cut at
4,500 steps (3,883, 4,302, 4,403 on average), player 1 winning 43%, 36%, 41% and player 2
45%, 43%, 34%.

Quirks "chip8": written for it; no shift, BNNN or 8XY1-3, and I is set before every FX55/FX65.
The pace is the display wait's (a sprite ends its frame): about 8 frames (2 steps) a move. The keys are
read in two frames opened by a sprite of no rows (DXY0: on CHIP-8 it draws nothing): up and
down for both players in the first, left and right in the second, so a profile without the
display wait would read them at other times. Timers: real 60 Hz; the delay timer times the
48-frame pause before the first round and the 32 frames of the score between rounds. Start-up:
10 frames (the start screen drawn), the level key held 3 frames, 25 frames: inside the pause,
so the first round's start row and obstacles are drawn from each episode's reset key.
Episodes are cut at 4,500 steps (5 minutes).
"""

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.env.games._own import level_specs, own_game_spec
from octax_core.env.games.spec import Seats, register_value

X1, Y1, SCORE1, SCORE2, X2, Y2, DIR1, DIR2, GAME_OVER = 3, 4, 5, 6, 7, 8, 9, 10, 14
WIN = 5
UP, LEFT, RIGHT, DOWN = 0, 1, 2, 3  # the ROM's headings: a heading and its way back sum to 3
# numpy, not jnp: a module of the registry must not start JAX's backend at import (a user sets the
# device count after `import octax_core`)
_STEP = np.array([[0, -1], [-1, 0], [1, 0], [0, 1]])  # (dx, dy) per heading
_ACTION = np.array([1, 3, 4, 2])  # the action whose key asks for each heading
LOOKAHEAD = 12
_PREFERENCE = (np.array([2, 0, 3, 1]), np.array([2, 3, 0, 1]))  # per seat, by heading (higher first)

_LEVELS = (  # level: pairs of obstacles
    (1, 0),
    (2, 3),
    (3, 6),
)
DEFAULT_LEVEL = 2


def _scores(state):
    """(V5 - V6, V6 - V5): a round is +1 to its winner and -1 to the other."""
    rounds = jnp.stack([register_value(state, SCORE1), register_value(state, SCORE2)])
    return rounds - rounds[::-1]


def _lit(state, x, y):
    """Whether cell (x, y) is lit (off the 32x16 cells counts as lit)."""
    inside = (x >= 0) & (x < 32) & (y >= 0) & (y < 16)
    px, py = jnp.clip(2 * x, 0, 63), jnp.clip(2 * y, 0, 31)
    word = state.screen[py, px // 32]
    bit = (word >> (31 - px % 32).astype(word.dtype)) & 1
    return ~inside | (bit == 1)


def scripted_policy(state, seat: int) -> jax.Array:
    """Of the headings open (not the way back), the one with the longest free run of cells ahead
    (up to LOOKAHEAD); on a tie the present heading (no-op), then inwards, up, down. The two
    seats' preferences mirror each other, so the bot plays either side alike."""
    x = register_value(state, X1 if seat == 0 else X2)
    y = register_value(state, Y1 if seat == 0 else Y2)
    heading = register_value(state, DIR1 if seat == 0 else DIR2)
    ahead = jnp.arange(1, LOOKAHEAD + 1)

    def free_run(h):
        step = jnp.asarray(_STEP)[h]
        lit = jax.vmap(lambda k: _lit(state, x + k * step[0], y + k * step[1]))(ahead)
        return jnp.argmax(jnp.append(lit, True))  # cells before the first lit one

    runs = jax.vmap(free_run)(jnp.arange(4))
    # ties: the present heading, then inwards (player 1 right, player 2 left: mirror images), up, down
    order = jnp.asarray(_PREFERENCE[seat])
    value = jnp.where(jnp.arange(4) + heading == 3, -1, runs * 8 + (jnp.arange(4) == heading) * 4 + order)
    best = jnp.argmax(value)
    return jnp.where(best == heading, 0, jnp.asarray(_ACTION)[best]).astype(jnp.int32)


SEATS = Seats(
    action_keys=((0x5, 0x8, 0x7, 0x9), (0xC, 0xD, 0xE, 0xF)),  # up, down, left, right
    score_fn=_scores,
    zero_sum=True,
    names=("left cycle", "right cycle"),
    scripted_policy=scripted_policy,
    mirror="left-right",  # measured: docs/multiplayer.md, "Mirrored seats"
    mirror_actions=(0, 1, 2, 4, 3),  # up and down stay, left and right swap
)


def _spec(game_id: str, level: int, pairs: int):
    obstacles = f"{pairs} pairs of obstacles" if pairs else "no obstacles"
    return own_game_spec(
        game_id, level,
        title=f"Cycles, level {level} ({obstacles}; two players, first to {WIN} rounds)",
        rom_file="cycles.ch8",
        rom_sha1="c53b930cdd5022b167fc0ad2331d8834b290a6e6",
        action_keys=SEATS.action_keys[0],
        lives_fn=lambda state: WIN - register_value(state, SCORE2),
        seats=SEATS,
        category="planning",
        description=f"Light cycles: steer your cycle (player 1: keys 5 up, 8 down, 7 left, 9 right; "
                    f"player 2: C, D, E, F) and outlast the other; a cycle that runs into the wall, a "
                    f"trail or an obstacle ({obstacles}) loses the round. First to {WIN} rounds ends "
                    f"the game (VE == 1). Two players: zero-sum, +1/-1 per round; one player (against "
                    f"a cycle that runs straight on): +1 per round won.",
    )


SUITE = "ours"
SPECS = level_specs("Cycles", _LEVELS, DEFAULT_LEVEL, _spec)
