"""Sens8tion (Octojam 3, archive "sens8tion"): gun kata after the film Equilibrium, in SUPER-CHIP hires.

### Observation
The screen, uint8 (frames_per_step, 64, 128): the cleric (Preston) in the middle, posing, with
antagonists (troopers, katana men, corpses) in the 8 zones around him, the round's time bar on
the left and the 'suck' bar on the right; between battles, text cutscenes (some letters dance).

### Actions
0: no-op; 1..9: key 1..9, the pad 1 2 3 / 4 5 6 / 7 8 9 around the cleric: keys 1-4 and 6-9
shoot at the antagonist in that zone (`input_loop`: a key equal to the last one is ignored, so
two zones in a row take two keys); 5 stands idle, and is the key every cutscene waits for
(`cutsceneWait5`, `danceTextLoop`: they go on while key 5 is held, else wait forever).

### Reward
+1 per antagonist killed, counted towards the story's four battles, 136 kills in all. The ROM
keeps, per battle, `kills` (V5, `:alias kills v5`): `main` sets it to the battle's quota (32
troopers, 48 troopers in close, 48 in the corridor, 8 katana men) and every kill takes one off
(`fightLoop` with 6 at the end of a round for a shot antagonist, or with 40 on a corridor hit);
the battle (`game_loop`, called from `main` at 0x2CC, 0x30C, 0x33C via `game_loop_skip_bars`,
0x35C) returns when it reaches 0. The score is the sum of the quotas of the battles `main` has
passed plus quota - V5 for the one it is in (where `main` is: pc at depth 0, else the call on the
bottom of the stack). Battles 1, 2 and 4 pay at the end of each round (a round is 14 loops of
8 frames, the left bar), the corridor at each hit. The final boss (0x384) and the `suck` bar
(V6: +1 per antagonist left unshot at a round's end, up to 14, never read again) pay nothing.

### Termination
The story's end: after the boss's time runs out `main` clears the screen, buzzes and executes
00FD `exit` (0x386..0x38F; the env also ends an episode on 00FD itself). There is no game over:
the battles go on until their quota is killed, whatever the suck bar shows. A player that never
holds key 5 stays in a cutscene until truncation.

Options from the archive: SUPER-CHIP, tickrate 20, its quirks (shift, load/store, jump) and
colours. The ROM's source reassembles to the same length and labels; 24 bytes differ (the
comparison pseudo-ops' temporary register, ve here). Start-up, 2,717 frames: the title's FX0A
(key 5 held 2 frames, released), then key 5 held 2,644 frames through the tutorial battle and
the cutscenes up to KILL THEM before battle 1, whose dance loop then waits (40 frames) for key 5;
so battle 1's first spawns (`random`) and all later ones are drawn from each episode's reset key.
Random play finishes the story in about 2,000 steps; episodes are cut at 4,500 steps.

What the reward does not tell: the kills a battle needs are fixed, and antagonists appear only
at a round's end (each empty zone with probability 1/2, all of them cleared then), so any player
that keeps pressing keys collects all 136; a better shooter gets them in fewer rounds (random
play hits about 3 of 4 antagonists a round) and fills the suck bar less, which is seen on the
screen but not scored.
"""

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import key_mask, register_value

KILLS = 5  # V5 `kills`
BATTLES = ((0x2CC, 32), (0x30C, 48), (0x33C, 48), (0x35C, 8))  # `main`'s battle calls, each quota
THE_END = (0x386, 0x390)  # `gameTestJump`: clear, buzzer, exit


def main_position(state):
    """Where `main` is: pc when nothing is called, else the call at the bottom of the stack."""
    return jnp.where(state.sp == 0, state.pc.astype(jnp.int32), state.stack[0].astype(jnp.int32) - 2)


def _score(state):
    at, kills = main_position(state), register_value(state, KILLS)
    score = jnp.int32(0)
    for site, quota in BATTLES:
        score = score + jnp.where(at > site, quota, jnp.where(at == site, quota - kills, 0))
    return score


def _over(state):
    at = main_position(state)
    return (at >= THE_END[0]) & (at < THE_END[1])


SPECS = (archive_spec(
    "sens8tion",
    id="Sens8tion",
    rom_sha1="58f7ce407aedf456dc8992342f4a6f9f0647383b",
    action_keys=(1, 2, 3, 4, 5, 6, 7, 8, 9),
    score_fn=_score,
    terminated_fn=_over,
    startup=((0, 30), (key_mask(5), 2), (0, 1), (key_mask(5), 2644), (0, 40)),
    max_episode_steps=4500,
    category="reaction",
    description="Shoot the antagonists in the 8 zones around the cleric (keys 1-4, 6-9; key 5 "
                "stands idle and advances the cutscenes) through four battles; reward +1 per "
                "kill towards each battle's quota (136 in all); the game ends with the story, "
                "after the final boss.",
),)
