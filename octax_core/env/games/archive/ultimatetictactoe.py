"""Ultimate Tic-tac-toe (Octojam 1, archive "ultimatetictactoe"): X and O take turns on nine boards.

A two-player game only (`solo=False`: `octax_core.make_multi("UltimateTicTacToe")`): the players
share one cursor and the same keys, in turn. The rules are ultimate tic-tac-toe's: the cell you
play within its small board sends the other player to the matching small board (anywhere, when
that board is decided); three in a row wins a small board, three small boards in a row the game.

### Observation
The screen, uint8 (frames_per_step, 64, 128) (SUPER-CHIP hires): nine 3x3 boards (cells 7
pixels apart, x 33..89, y 2..58), the X and O marks, a won board filled with its winner's mark,
and the cursor, the mover's mark XOR-drawn on its cell. In `make_multi` the last plane is the
player plane.

### Actions
Per seat, 0: no-op, 1: key 5 (cursor up), 2: key 8 (down), 3: key 7 (left), 4: key 9 (right),
5: key 6 (place the mark). Input is FX0A (`button := key`, 0x20A): a key counts once, when it is
released, so a key held for several steps is one move, and two presses need a no-op (or another
key) between them. `check-bounds` keeps the cursor inside the small board the mover is sent to.
Both seats hold the same keys: the seat whose turn it is not has only no-op open.

Legal actions (`Seats.legal_fn`): the moves are always open; place is open only on an empty cell,
read from the screen at the cursor (row 0 of a cell: both marks light its third pixel, X also its
second; the cursor XORs the mover's mark there). The ROM ignores a place on a taken cell (its
sprite collides, `place-marker` undraws it and returns), so the mask only closes what would be a
wasted move. It is exact while the ROM waits at 0x20A, where it spends most of its time; while it
works out a move (7 to 18 steps after a place, measured) every action is open.

### Reward
Zero-sum: +1 to the winner and -1 to the loser when the game is won, 0 otherwise. The ROM's
`winner` (0x3A2) runs when `checkfullwin` finds three won boards in a row, with the winning mark
in VE (1 X, 2 O; `checkfullwin` copies a board's owner, `data + b` AND 3, into VE before testing
its lines, so VE is read only inside `winner`).

### Termination
`winner` runs: it wipes the boards' results, waits for a key and calls `main` again (0x3A2..0x3D7
or what it called, `in_routine`). Or every small board is decided (`data` 0x833..0x83B all
non-zero: won, 1 or 2, or full, 4) with no three in a row: nothing can be placed any more and the
ROM has no draw screen, so the episode ends there as a draw (reward 0). Cut at 6,000 steps.

Whose turn: `currplayer` (VD): 0 X (seat 0, moves first), 1 O (seat 1); `place-marker` flips it
as soon as a mark is drawn.

Scripted policy (`Seats.scripted_policy`): reads the 81 cells off the screen and, in the board
it is sent to, plays the cell that wins a small board (first one that wins the game), else one
that blocks the other's small-board win (first one that would lose the game), avoiding cells that
send the other player to a board it can win or to a decided board (a free move), then the cell
nearest the centre of its board (then the first in reading order); it steers the cursor there one
key a step (a no-op while the ROM holds a key it has seen) and places.

Measured (`make_multi`, frames_per_step 4, 64 envs x 12,000 steps with autoreset, the episodes
that finished; cut at 6,000 steps): random vs random (each seat uniform over its legal actions),
X wins 0.43, O 0.29, the rest drawn or cut (23 of 195), mean 3,185 steps a game; scripted X vs
random wins 0.92 and loses none (mean 1,277 steps: the random side's slow moves make most of
it), random X vs scripted O: O wins 0.88, X 0.01 (1,406 steps).

Options from the archive: tickrate 7 (a place keeps the ROM busy for 7 to 18 steps), no shift
or load/store quirks, its colours. The ROM draws no random numbers: a game depends only on the
moves. Start-up: 30 frames, the boards drawn and the ROM waiting for the first key with the cursor
in the middle cell.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import Seats, in_routine, ram_value

CURRENT_PLAYER, CURSOR_X, CURSOR_Y, CURRENT_BOARD, WINNER_MARK = 0xD, 0xC, 0xB, 0x9, 0xE
KEY_WAIT_PC = 0x20A  # main's `button := key`
WINNER = (0x3A2, 0x3D8)  # `winner`, up to `check-wins`
DATA = 0x832  # `: data`, the small boards' results at data + 1 .. data + 9
KEYS = (0x5, 0x8, 0x7, 0x9, 0x6)
UP, DOWN, LEFT, RIGHT, PLACE = 1, 2, 3, 4, 5
CELL_X = tuple(33 + 7 * i for i in range(9))  # the cells' top-left pixels (hires)
CELL_Y = tuple(2 + 7 * i for i in range(9))
X_MARK, O_MARK = 0x68, 0x30  # row 0 of `cross` and `circle`


def _lines() -> np.ndarray:
    """(72, 3): every small board's 8 lines, as cell indices row * 9 + column."""
    lines = []
    for board in range(9):
        top, left = 3 * (board // 3), 3 * (board % 3)
        cell = lambda r, c: (top + r) * 9 + left + c
        lines += [[cell(r, 0), cell(r, 1), cell(r, 2)] for r in range(3)]
        lines += [[cell(0, c), cell(1, c), cell(2, c)] for c in range(3)]
        lines += [[cell(0, 0), cell(1, 1), cell(2, 2)], [cell(0, 2), cell(1, 1), cell(2, 0)]]
    return np.array(lines)


LINES = _lines()
INCIDENCE = np.zeros((LINES.shape[0], 81), np.int32)  # line x cell
INCIDENCE[np.arange(LINES.shape[0])[:, None], LINES] = 1
CELL_BOARD = np.array([(r // 3) * 3 + c // 3 + 1 for r in range(9) for c in range(9)])  # the ROM's currboard 1..9
CELL_SENDS = np.array([(r % 3) * 3 + c % 3 + 1 for r in range(9) for c in range(9)])  # the board a place sends to
LINE_BOARD = np.repeat(np.arange(9), 8)  # the small board (0..8) of each of `LINES`
BIG_LINES = np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8], [0, 3, 6], [1, 4, 7], [2, 5, 8], [0, 4, 8], [2, 4, 6]])
BIG_INCIDENCE = np.zeros((8, 9), np.int32)  # line of boards x board
BIG_INCIDENCE[np.arange(8)[:, None], BIG_LINES] = 1
CELL_CENTRED = np.array([(r % 3 == 1) + (c % 3 == 1) for r in range(9) for c in range(9)])  # 2 centre, 1 edge, 0 corner


def _pixel(state, x, y):
    """Hires pixel (x, y) of the screen (arrays of coordinates), 0 or 1."""
    words = state.extension.grid[0][y, x // 32]
    return ((words >> (31 - x % 32).astype(jnp.uint32)) & 1).astype(jnp.int32)


def _cursor_cell(state):
    col = (state.V[CURSOR_X].astype(jnp.int32) - CELL_X[0]) // 7
    row = (state.V[CURSOR_Y].astype(jnp.int32) - CELL_Y[0]) // 7
    return row, col


def cells(state):
    """(81,) int32 per cell, row * 9 + column: 0 empty, 1 X, 2 O, read from row 0 of each cell with
    the cursor (the mover's mark, XOR-drawn while the ROM waits for a key) taken out."""
    xs = jnp.asarray(np.tile(CELL_X, 9), jnp.int32)
    ys = jnp.asarray(np.repeat(CELL_Y, 9), jnp.int32)
    second, third = _pixel(state, xs + 1, ys), _pixel(state, xs + 2, ys)
    row, col = _cursor_cell(state)
    at_cursor = (jnp.arange(81) == row * 9 + col) & (state.pc == KEY_WAIT_PC)
    cursor = jnp.where(state.V[CURRENT_PLAYER] == 0, X_MARK, O_MARK)
    second = second ^ (at_cursor & ((cursor >> 6) & 1).astype(jnp.bool_)).astype(jnp.int32)
    third = third ^ at_cursor.astype(jnp.int32)  # both marks light the third pixel
    return jnp.where(third == 1, jnp.where(second == 1, 1, 2), 0)


def _mover(state):
    return (state.V[CURRENT_PLAYER] & 1).astype(jnp.int32)


def _legal(state):
    row, col = _cursor_cell(state)
    empty = cells(state)[jnp.clip(row, 0, 8) * 9 + jnp.clip(col, 0, 8)] == 0
    place = empty | (state.pc != KEY_WAIT_PC)
    return jnp.array([True, True, True, True, True, True]).at[PLACE].set(place)


def _won(state):
    return in_routine(state, *WINNER)


def _boards(state):
    return jnp.stack([ram_value(state, DATA + b) for b in range(1, 10)])


def _over(state):
    return _won(state) | (_boards(state) != 0).all()


def _outcome(state):
    winner_seat = state.V[WINNER_MARK].astype(jnp.int32) - 1  # 1 X -> seat 0, 2 O -> seat 1
    sign = jnp.where(winner_seat == 0, 1, -1)
    value = jnp.where(_won(state) & ((winner_seat == 0) | (winner_seat == 1)), sign, 0)
    return jnp.stack([value, -value]).astype(jnp.int32)


def _completes(owner, decided, mark):
    """(9,) bool: winning this small board gives `mark` three boards in a row (`owner`: the boards'
    winners, 0 where open or tied; `decided`: won or tied)."""
    big = jnp.asarray(BIG_INCIDENCE)
    two_and_open = ((big @ (owner == mark).astype(jnp.int32)) == 2) & ((big @ (~decided).astype(jnp.int32)) == 1)
    return ((big.T @ two_and_open.astype(jnp.int32)) > 0) & ~decided


def scripted_policy(state, seat: int):
    """One ply with the nine boards in view: win a small board (first one that wins the game),
    else block one (first one that would lose it), avoiding cells that send the other player to a
    board it can win or to a free move; then the most central cell. Steers there one key a step."""
    board = cells(state)
    owner = _boards(state) & 3  # 1 X, 2 O, 0 open or tied (4)
    decided = _boards(state) != 0
    mine, theirs = 1 + seat, 2 - seat
    incidence = jnp.asarray(INCIDENCE)
    count = lambda mark: incidence @ (board == mark).astype(jnp.int32)  # per line
    open_board = ~decided[jnp.asarray(LINE_BOARD)]
    winning_lines = (count(mine) == 2) & (count(theirs) == 0) & open_board
    blocking_lines = (count(theirs) == 2) & (count(mine) == 0) & open_board
    wins = (incidence.T @ winning_lines.astype(jnp.int32)) > 0
    blocks = (incidence.T @ blocking_lines.astype(jnp.int32)) > 0
    cell_board = jnp.asarray(CELL_BOARD) - 1
    game_win = wins & _completes(owner, decided, mine)[cell_board]
    game_save = blocks & _completes(owner, decided, theirs)[cell_board]
    threat = jnp.zeros(9, jnp.int32).at[jnp.asarray(LINE_BOARD)].max(blocking_lines.astype(jnp.int32)) > 0
    # a cell's place in its board sends the other player there (anywhere, when that board is decided)
    sends = jnp.asarray(CELL_SENDS) - 1
    sent_danger = threat[sends] | decided[sends]
    sent_to = state.V[CURRENT_BOARD].astype(jnp.int32)
    allowed = (board == 0) & ((sent_to == 0) | (jnp.asarray(CELL_BOARD) == sent_to))
    value = (64 * game_win + 32 * game_save + 8 * wins + 4 * blocks - 6 * sent_danger
             + jnp.asarray(CELL_CENTRED) + 20)
    target = jnp.argmax(jnp.where(allowed, value * 100 - jnp.arange(81), -1))
    row, col = _cursor_cell(state)
    action = jnp.where(row > target // 9, UP, jnp.where(row < target // 9, DOWN,
                       jnp.where(col > target % 9, LEFT, jnp.where(col < target % 9, RIGHT, PLACE))))
    waiting = (state.pc == KEY_WAIT_PC) & (state.key_wait == 0xFF)  # release a key the ROM has seen
    return jnp.where(waiting & allowed.any(), action, 0).astype(jnp.int32)


SPECS = (archive_spec(
    "ultimatetictactoe",
    id="UltimateTicTacToe",
    rom_sha1="12572c9e957cace53076d1656ea1b12cd0f331af",
    action_keys=KEYS,
    score_fn=lambda state: _outcome(state)[0],
    terminated_fn=_over,
    startup=((0, 30),),
    max_episode_steps=6000,
    solo=False,
    seats=Seats(
        action_keys=(KEYS, KEYS),
        score_fn=_outcome,
        turn_fn=_mover,
        legal_fn=_legal,
        zero_sum=True,
        names=("X", "O"),
        scripted_policy=scripted_policy,
    ),
    category="planning",
    description="X and O take turns to move one cursor (keys 5/8/7/9) and place (key 6) on nine "
                "tic-tac-toe boards, each move sending the other to a board; reward +1 for the "
                "winner and -1 for the loser; the game ends when three won boards make a line.",
),)
