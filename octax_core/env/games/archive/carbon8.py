"""Carbon8 (Octojam 5, archive "carbon8"): freeze a slab of carbonite that hits two temperature goals.

### Observation
The screen, uint8 (frames_per_step, 32, 64): the freezing chamber with the slab growing between two
claws, the internal and external temperature bars with their goal ranges marked (left), the vent
knob (x 16), the carbonite power bar (x 24), the filler knob (x 40) and the scanner (x 48..62).

### Actions
0: no-op, 1: key 4 (vent +, `:alias knob1 v9`), 2: key 7 (vent -), 3: key 9 (carbonite
power +, `:alias bar1 vb`), 4: key 8 (power -), 5: key D (filler +, `:alias knob2 va`), 6: key E (filler -).
These are all the keys the main loop reads (its `control_table` jump table). Vent lets warm air
in, power cools the target, filler adds mass without cooling; the slab grows by `bar1 / 2 + knob2`
per loop (`fill_remaining` v6 overflows into `fill_target` v7, done past 0x0F).

### Reward
+1 for each of the two temperatures inside its goal range as the slab completes (0 to 2). The ROM
keeps no score, only Jabba's verdict at the end of a level: the external (`temp_ex` vC) and
internal (`temp_in` vD) temperatures are each compared with the level's goal range (`goals` at
0xAC9, 8 bytes a level: external min/max in bytes 0-1, internal min/max in bytes 4-5) at the
instant the slab completes. The reward is that verdict: +1 for each temperature inside its range
(0, 1 or 2), given on the step the slab completes; 0 on every other step. It is read from the same
registers and table the ROM's `level_complete` judge reads, before the judge screen reuses them.

### Termination
The slab completes: pc in `level_complete` (0x3E6) up to `judge_review`'s loop (0x4A0); the ROM
stops at once on `v0 := key` there (0x3F2), which needs a key pressed and released, so a step
always ends inside it. An episode is one level, the first (the mynock, `start_level` 0).

Options from the archive: tickrate 15, no quirks, real timers (the main loop paces itself at one
pass per 3 frames with the delay timer; the temperatures move every `time_between_pulses` = 10
passes). The slab never grows while power and filler are both 0 (the start), so an idle agent
runs to the 4,500-step cut (5 minutes). Start-up: 60 frames (title drawn), key 4 held and
released on the title's `v0 := key`, on the level-name page and on the mynock's portrait, then 6
frames of the level's setup. The ROM draws no random numbers: a level plays the same for every reset
key and depends only on the actions.
"""

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import key_mask, ram_value

LEVEL_COMPLETE = (0x3E6, 0x4A0)  # `level_complete` .. `judge_review`
GOALS = 0xAC9  # `goals`: 8 bytes per level
TEMP_EX, TEMP_IN, LEVEL = 12, 13, 14  # `:alias temp_ex vc`, `temp_in vd`, `level_number ve`


def _slab_done(state):
    return (state.pc >= LEVEL_COMPLETE[0]) & (state.pc < LEVEL_COMPLETE[1])


def _verdict(state):
    """Temperatures inside the level's goal ranges (0..2) once the slab is done, else 0."""
    base = GOALS + state.V[LEVEL].astype(jnp.int32) * 8
    ex, tin = state.V[TEMP_EX], state.V[TEMP_IN]
    ex_ok = (ex >= ram_value(state, base, 1)) & (ex <= ram_value(state, base + 1, 1))
    in_ok = (tin >= ram_value(state, base + 4, 1)) & (tin <= ram_value(state, base + 5, 1))
    hits = ex_ok.astype(jnp.int32) + in_ok.astype(jnp.int32)
    return jnp.where(_slab_done(state), hits, 0)


_PRESS_4 = ((key_mask(4), 3), (0, 60))

SPECS = (archive_spec(
    "carbon8",
    id="Carbon8",
    rom_sha1="2e0f2268c9a3be0fbb839f918336f161815bb80a",
    action_keys=(4, 7, 9, 8, 13, 14),
    score_fn=_verdict,
    terminated_fn=_slab_done,
    startup=((0, 60),) + _PRESS_4 * 3,
    max_episode_steps=4500,
    category="resources",
    description="Run the carbonite freezing chamber: keys 4/7 open or close the warm-air vent, 9/8 "
                "raise or lower the cooling power, D/E raise or lower the filler; the slab grows "
                "with power and filler. Reward +1 for each of the external and internal "
                "temperatures inside its goal range when the slab completes, which ends the episode.",
),)
