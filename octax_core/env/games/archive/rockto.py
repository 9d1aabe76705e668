"""Rockto (Octojam 1, archive "rockto"): dig for diamonds and reach the exit without being crushed.

### Observation
The screen, uint8 (frames_per_step, 64, 128; SUPER-CHIP hires): a 16x7 grid of 8x8 tiles (walls,
dirt, boulders, diamonds, the player, the exit) and a HUD row with the level number and the
diamonds left.

### Actions
0: no-op, 1: key 7 (left), 2: key 9 (right), 3: key 5 (up), 4: key 8 (down). The player moves
one tile per key press, read by FX0A (`dir := key` in `move-player`, 0x6F0), so a move is a press
then a release, and a press while the ROM is busy (moving boulders at 15 instructions a frame)
is lost. Moving into dirt digs it; a boulder can be pushed sideways into a blank tile. Key 1
(`MOVE_RESET`, restart the level) is not offered.

### Reward
+1 per diamond collected, +5 per level completed (reaching the exit once no diamonds are left).
The ROM keeps the diamonds left in `:alias diamonds va` and the level in `:alias level-no vb`;
the score is the diamonds and bonuses of the levels before (from the level data: 4, 8, 7, 1, 5
diamonds) plus this level's diamonds minus va. va is only meaningful inside `move-player`
(0x6E8..0x795 and what it calls), after a death, and in the two instructions of `main` before
`level-no += 1` (0x82C..0x82F); elsewhere (`start-level` recounting the diamonds) this level
counts 0, so the score never jumps or drops.

### Termination
A boulder or diamond falls on the player (`apply-gravity` sets `:alias dead vc` to `DEAD_YES`; the
game would restart the level), or all five levels are done (level-no 6: the ROM would read code
as a sixth level).

Options from the archive: SUPER-CHIP, tickrate 15. The game has no random numbers: levels are
fixed and the episode depends only on the agent's moves. Start-up: 10 frames of title, key 5 held
2 frames on the title's FX0A, then 300 frames while `start-level` draws level 1, so episodes
start at the first move's key wait. Episodes are cut at 4,500 steps (5 minutes).
"""

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import in_routine, key_mask, register_value

LEVEL_NO, DIAMONDS, DEAD = 0xB, 0xA, 0xC  # `:alias level-no vb`, `diamonds va`, `dead vc`
DIAMONDS_IN = (0, 4, 8, 7, 1, 5, 0)  # per level-no: the 4 tiles in `level1`..`level5`
EXIT_BONUS = 5
# What levels 1..level-1 earned: all their diamonds and the exit bonus.
EARNED_BEFORE = tuple(sum(DIAMONDS_IN[:level]) + EXIT_BONUS * max(level - 1, 0) for level in range(7))
MOVE_PLAYER = (0x6E8, 0x796)  # `move-player`, up to `apply-gravity`
LEVEL_DONE = (0x82C, 0x830)  # `main`: `if dead == DEAD_NO then level-no += 1`
LAST_LEVEL = 5


def _score(state):
    """Diamonds collected plus 5 per level done; this level's diamonds only where va is valid."""
    level = jnp.clip(register_value(state, LEVEL_NO), 0, LAST_LEVEL + 1)
    playing = (in_routine(state, *MOVE_PLAYER) | (state.V[DEAD] == 1)
               | ((state.pc >= LEVEL_DONE[0]) & (state.pc < LEVEL_DONE[1])))
    collected = jnp.where(playing, jnp.asarray(DIAMONDS_IN)[level] - register_value(state, DIAMONDS), 0)
    return jnp.asarray(EARNED_BEFORE)[level] + collected


SPECS = (archive_spec(
    "rockto",
    id="Rockto",
    rom_sha1="b76fbca2ec089c7e77f4a2f754db37854b99debc",
    action_keys=(7, 9, 5, 8),
    score_fn=_score,
    terminated_fn=lambda state: (state.V[DEAD] == 1) | (state.V[LEVEL_NO] > LAST_LEVEL),
    startup=((0, 10), (key_mask(5), 2), (0, 300)),
    max_episode_steps=4500,
    category="planning",
    description="Dig through the cave with keys 7/9/5/8 (left, right, up, down), collect every "
                "diamond and reach the exit; reward +1 per diamond and +5 per level; the game ends "
                "when a falling boulder or diamond hits the player, or after level 5.",
),)
