"""RPS (Octojam 1, archive "RPS"): rock-paper-scissors against the CPU, up to the 1,000th win.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the battle screen with your wins (3 digits, top
right); after a throw the CPU's hand (left) and yours (right), WIN / LOSE / TIE and two faces,
all erased again before the next throw.

### Actions
0: no-op, 1: key A (rock), 2: key 0 (paper), 3: key B (scissors): `body` sets `player_choice`
from them (0xA, 0x0, 0xB) and waits again for any other key. Input is FX0A (0x873): a throw
counts once, when its key is released, so a key held for several steps is one throw.

### Reward
+1 per round won: the change of the wins the ROM keeps as three decimal digits, `score` (V0,
ones), `score2` (V1, tens), `score3` (V2, hundreds). `body` adds 1 to V0 after a win (losses
and ties score nothing) and `draw_score` carries a 10 into the next digit; the score is
100 V2 + 10 V1 + V0, less the carry not yet finished when a step ends between its two
instructions (pc 0x9AB: V1 raised, V0 still 10; pc 0x9B3: V2 raised, V1 still 10), so it never
jumps. The CPU's hand (`cpu_choice`, from `random_cpu` drawn on every pass of `main` before
`body` waits for the key: about 1/3 each) is not shown before the throw, so every throw wins
with chance 1/3 whatever the policy: only the pace of throws changes the return, and the pause
after each round (below) makes most of a round's length.

### Termination
The 1,000th win, the ROM's only end (its comment says 100 points, but it tests the hundreds
digit): `draw_score` finds `score3` at 10 (0x9B5), zeroes the three digits, clears the screen,
sets `game_mode` (VA, `:alias game_mode va`) to 5 and calls `main`, which from then on only
shows the "oh god" screen and waits with FX0A (0x815): any key shows it again, so the game
never goes on. V2 at 10, the pc in that block (0x9B9..0x9C6) or in what it called, or VA at 5
is the end, where the score reads 1,000 (the digits the block zeroes are not a loss). About
3,000 rounds (70,000 steps) away, it lies far beyond the default cut: in practice episodes are
cut, not ended.

Options from the archive: tickrate 7, Octo's default quirks (no shift or load/store quirks),
its colours; the ROM was built by an older Octo (84 bytes differ from our assembly: its
comparisons use VE, not VF, as their temporary) with every label where the source puts it.
After each throw `in_delay` counts V7 to 160 (480 instructions: about 70 frames, 17 steps)
before erasing the hands, so a round takes about 23 steps (a win every 70 steps or so).
Start-up: 40 frames (the title drawn), key 1 held 2 frames, 40 frames (help 1), key 1, 40
frames (help 2), then key 1 held 2 frames: that FX0A completes when the first env step
releases it (key 1 is not an action), so the battle screen is drawn and every CPU hand is drawn
from the episode's reset key. Episodes are cut at 4,500 steps (5 minutes, about 195 rounds).
"""

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, register_value

ONES, TENS, HUNDREDS, GAME_MODE, THE_END = 0, 1, 2, 10, 5  # V0, V1, V2, VA and its easter-egg mode
TENS_CARRIED, HUNDREDS_CARRIED = 0x9AB, 0x9B3  # `v0 := 0` after `v1 += 1`, `v1 := 0` after `v2 += 1`
ZEROING = (0x9B9, 0x9C7)  # the 100th win: zero the digits, clear, game_mode := 5, call main
WINS_TO_END = 1000


def _finished(state):
    return ((register_value(state, HUNDREDS) >= 10) | in_routine(state, *ZEROING)
            | (state.V[GAME_MODE] == THE_END))


def _wins(state):
    digits = (100 * register_value(state, HUNDREDS) + 10 * register_value(state, TENS)
              + register_value(state, ONES))
    carrying = (10 * (state.pc == TENS_CARRIED) + 100 * (state.pc == HUNDREDS_CARRIED)).astype(jnp.int32)
    return jnp.where(_finished(state), WINS_TO_END, digits - carrying)


SPECS = (archive_spec(
    "RPS",
    id="RPS",
    rom_sha1="a6f3ac2d89cdc1d7b22013301863bad6a4fb7318",
    action_keys=(0xA, 0x0, 0xB),
    score_fn=_wins,
    terminated_fn=_finished,
    startup=((0, 40), (key_mask(1), 2), (0, 40), (key_mask(1), 2), (0, 40), (key_mask(1), 2)),
    max_episode_steps=4500,
    category="reaction",
    description="Throw rock (key A), paper (key 0) or scissors (key B) against the CPU's hidden "
                "random hand; reward +1 per round won; the game ends only at the 1,000th win.",
),)
