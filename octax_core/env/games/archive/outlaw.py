"""Outlaw (archive "outlaw"): win a gunfight against a randomly moving outlaw across a cactus.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the player's gunslinger on the left (x 1..20), the
cactus in the middle (x 28..35), the outlaw on the right (x 36..55), bullets as single pixels,
and a line on the bottom row (the ROM draws it 2 rows high at y 31, so it wraps to the top row).

### Actions
0: no-op, 1: key 6 (fire), 2: key 5 (up), 3: key 8 (down), 4: key 7 (left), 5: key 9 (right).
These are all the keys the ROM reads (`fire-left-bullet`, `move-left-player`). One bullet at a
time; the cactus stops it. The ROM fires an angled, ricocheting shot when 5 or 8 is held with 6,
which one held key cannot do, so the agent shoots straight: over the cactus from the top rows
(`lefty` 1..3) or beside it, when the outlaw walks there.

### Reward
+1 for shooting the outlaw, -1 for being shot: the ROM keeps no score, and an episode is one duel: +1 when the player shoots the outlaw, -1 when
the outlaw shoots the player, 0 on every other step. The outcome is read once the ROM sits in
`gameover` (0x39E..0x3AB, the 32-frame pause after a hit): `rightdead` (0x398) has erased the
outlaw's sprite, `leftdead` (0x3AC) the player's, so the outcome is whether the outlaw's 8x12 box at
(`rightx` v8, `righty` v7) is empty on the screen (nothing else is ever drawn there).

### Termination
A hit either way: pc in `gameover` (0x39E..0x3AB). The pause lasts 32 frames (8 steps) before the
ROM jumps back to `main` for the next duel, so a step always ends inside it.

Options from the archive: tickrate 15, Octo's default quirks. The ROM has no title screen: `main`
starts the duel at once, so there is no start-up, and every random draw (the outlaw's `do-brain`
moves, 1 in 8 a shot, and its bullet angles) comes from each episode's reset key. The outlaw is the
ROM's own AI (random moves); there is no second human player. Episodes are cut at 4,500 steps
(5 minutes), which a duel rarely reaches.
"""

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec

GAMEOVER = (0x39E, 0x3AC)  # `gameover` pause loop, up to `leftdead`
RIGHTX, RIGHTY = 8, 7  # `:alias rightx v8`, `:alias righty v7`


def _in_gameover(state):
    return (state.pc >= GAMEOVER[0]) & (state.pc < GAMEOVER[1])


def _outlaw_box_empty(state):
    """True when no pixel is lit in the outlaw's 8x12 sprite box (it was erased by `rightdead`)."""
    x = state.V[RIGHTX].astype(jnp.int32)
    y = state.V[RIGHTY].astype(jnp.int32)
    rows = jnp.arange(32)
    cols = jnp.arange(64)
    word = state.screen[:, cols // 32]  # (32, 64)
    pixels = (word >> (31 - cols % 32).astype(jnp.uint32)) & 1
    box = ((rows >= y) & (rows < y + 12))[:, None] & ((cols >= x) & (cols < x + 8))[None, :]
    return jnp.sum(jnp.where(box, pixels, 0)) == 0


def _duel_outcome(state):
    return jnp.where(_in_gameover(state), jnp.where(_outlaw_box_empty(state), 1, -1), 0).astype(jnp.int32)


SPECS = (archive_spec(
    "outlaw",
    id="Outlaw",
    rom_sha1="a9d3c975a5e733646a04f6e61deebcd0ad50f700",
    action_keys=(6, 5, 8, 7, 9),
    score_fn=_duel_outcome,
    terminated_fn=_in_gameover,
    startup=(),
    max_episode_steps=4500,
    category="reaction",
    description="A gunfight across a cactus: move with keys 5/8/7/9 and fire with 6 at a randomly "
                "moving outlaw; reward +1 for shooting him, -1 for being shot; the episode ends at "
                "the first hit either way.",
),)
