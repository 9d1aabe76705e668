"""Tank! (Octojam 5, archive "tank"): two-player artillery, turn by turn, on one keypad.

A two-player game only (`solo=False`: `octax_core.make_multi("TankArchive")`): both players aim
with the same keys in turn (hot seat), so one agent alone would play both tanks.

### Observation
The screen, uint8 (frames_per_step, 32, 64): a random sine-wave hill, the two tanks (their
centres at x 4 or 12 and 51 or 59: `random 8` is 0 or 8, less 4), the mover's marker over its
tank, its angle and power (3 digits each, top middle), the shell's trail (left on the screen until
the round ends), the explosion, and after each hit the score screen. In `make_multi` the last
plane is the player plane.

### Actions
Per seat, 0: no-op, 1: key 5 (Octo's W: power +1), 2: key 8 (S: power -1), 3: key 7 (A: angle
+1, towards the left), 4: key 9 (D: angle -1, towards the right), 5: key E (F: fire). `aim`
(0x6AF) reads W/S/A/D once per pass of its loop, a pass every 3 frames (`KEY_REPEAT_INTERVAL`),
and leaves it when F is held; the angle wraps 0..180, the power 1..100. Both seats hold the same
keys (the ROM has one set, the players take turns at the keypad): the seat whose turn it is not
has only no-op open (`legal_action_mask`), so the other seat's presses never reach the machine.

### Reward
Zero-sum: each seat's score is its hits minus the other's, so a hit is +1 for the seat credited
and -1 for the other. The ROM keeps the hits in RAM, `player1_data + 2` (0x2DE, left tank, seat 0)
and `player2_data + 2` (0x2E3, right tank, seat 1); `main` raises the shooter's on a hit on the
other tank (`COLLISION_P2` credits player 1, anything else player 2), so a shell that lands on its
own tank gives the point to the other side. `info["score"]` is the lead, (h1 - h2, h2 - h1).

### Termination
The ROM never ends: after each hit it shows the score, draws a new hill and a new turn order, and
goes on. Episodes end when either side has `HITS_TO_WIN` (3) hits, a best-of-five match; they are
cut at 4,500 steps.

Whose turn: `turn` (0x2E6), raised after every shot that misses (`add_to_var turn 1`) and drawn
at random (0 or 1) for each round: odd is the left tank (seat 0), even the right one (seat 1)
(`aim`: `v0 &= 1`, `player1_data` unless it is 0). `current_player` is that seat through the
whole turn: the aim, the shell's flight and the 100-frame pause after the explosion.
The aim lives in V7 (angle) and V6 (power) while `aim` runs, and is stored at `player_data + 3`
and `+ 4` when the shot is fired, so each tank keeps its aim from turn to turn (45 and 135 and
power 40 at first).

Scripted policy (`Seats.scripted_policy`): the left tank aims at 45, the right at 135, with the
power from `POWER_TABLE`: the power that lands the shell in the middle of the other tank's hitbox
(within 3 pixels across and 2 up or down, as `check_player_hitbox` tests) for the tanks' distance
(39, 47 or 55 pixels) and height difference, found by `lands` (this module), a step-for-step copy
of the ROM's fixed-point flight (`angle_to_vec2d`, `twos_add_frac`, gravity 1/2 a velocity unit a
frame) over a flat ground. It steers V7 and V6 to its aim, one key a step, and fires when both
are there; the hill may still block a shot.

Measured (`make_multi`, frames_per_step 4, 64 envs x 4,500 steps with autoreset, the episodes
that finished): random vs random, seat 0 wins 0.45 and loses 0.33 of 67 episodes (29 cut at 4,500
steps; mean return +0.22, 3,321 steps); scripted (seat 0) vs random wins 0.99 of 538 (mean
+2.86, 501 steps), random vs scripted (seat 1) loses all 486 (mean -2.85, 550 steps). Scripted
against scripted, 0.75 of 976 shots hit (the others hit the hill, or the flat-ground aim is off).

Options from the archive: tickrate 200, Octo's default quirks. The ROM was built by an older Octo
(120 bytes differ from our assembly: its comparisons use VE, not VF, as their temporary) with
every label where the source puts it. Start-up: 320 frames, into the title's last 200-frame
pause, so the hill, the tanks' places and the first mover are drawn from each episode's reset key.
"""

from __future__ import annotations

import jax.numpy as jnp

from octax_core.env.games.archive._program import archive_spec
from octax_core.env.games.spec import Seats, in_routine, ram_value

PLAYER1_DATA, PLAYER2_DATA = 0x2DC, 0x2E1  # posX, posY, score, angle, power
SCORE = (PLAYER1_DATA + 2, PLAYER2_DATA + 2)
TURN = 0x2E6  # `: turn 1`
AIM = (0x6AF, 0x79F)  # `aim`, up to `clear_print` (which it calls)
ANGLE, POWER = 7, 6  # `:alias angle v7`, `:alias power v6` inside `aim`
HITS_TO_WIN = 3
KEYS = (0x5, 0x8, 0x7, 0x9, 0xE)  # W, S, A, D, F on Octo's keyboard map
POWER_UP, POWER_DOWN, ANGLE_UP, ANGLE_DOWN, FIRE = 1, 2, 3, 4, 5
AIM_ANGLE = (45, 135)

_SIN = (0, 18, 36, 54, 72, 89, 106, 123, 138, 153, 168, 181, 193, 205, 215, 225, 233, 240, 246, 250, 253, 255, 255)
DISTANCES = (39, 47, 55)  # the tanks' x 8 +- 4 and 55 +- 4 (`random 8` is 0 or 8)
DY_RANGE = 16  # the table's rows: the other tank 16 pixels above .. 16 below
# [seat][distance][dy + 16]: the power `lands` picks (the middle of the first run of powers that hit).
POWER_TABLE = (
    ((60, 58, 57, 55, 55, 54, 53, 53, 51, 50, 50, 49, 48, 47, 47, 46, 46, 45, 45, 45, 43, 43, 43, 42, 42, 42, 40,
      40, 40, 40, 39, 39, 39),
     (62, 62, 61, 60, 59, 58, 57, 57, 56, 55, 54, 54, 53, 53, 52, 52, 51, 50, 50, 50, 49, 49, 48, 47, 47, 47, 46,
      46, 46, 46, 45, 45, 44),
     (66, 65, 64, 64, 63, 63, 61, 61, 60, 60, 58, 58, 58, 57, 57, 56, 55, 55, 54, 54, 53, 53, 53, 52, 52, 51, 51,
      51, 51, 50, 49, 49, 49)),
    ((38, 38, 39, 39, 39, 39, 40, 40, 40, 41, 42, 42, 43, 43, 43, 44, 45, 46, 46, 47, 47, 48, 48, 50, 50, 51, 53,
      53, 54, 55, 56, 58, 59),
     (43, 44, 44, 45, 45, 46, 46, 46, 46, 47, 47, 47, 48, 49, 49, 50, 50, 50, 52, 52, 53, 53, 53, 54, 55, 56, 57,
      57, 58, 59, 60, 61, 62),
     (48, 49, 50, 50, 50, 50, 51, 51, 51, 52, 53, 53, 53, 54, 54, 54, 55, 56, 56, 57, 57, 57, 59, 59, 60, 60, 61,
      62, 63, 63, 64, 64, 66)),
)


def _flight_velocity(angle: int, power: int) -> tuple[int, int]:
    """`angle_to_vec2d`: (vel_x, vel_y) as the ROM's bytes (vel_x two's complement left of 90)."""
    flip = angle > 90
    if flip:
        angle = 180 - angle
    index = angle >> 2
    vel_y = _SIN[index] * power // 256
    vel_x = _SIN[22 - index] * power // 256
    return ((-vel_x) & 0xFF if flip else vel_x), vel_y


def _twos_add_frac(whole: int, frac: int, velocity: int, step: int) -> tuple[int, int]:
    """The ROM's `twos_add_frac`: add a signed velocity byte (x2) to a fraction, carry into `whole`."""
    doubled = (velocity << 1) & 0xFF
    if velocity & 0x80:
        frac -= doubled ^ 0xFF
        if frac < 0:
            frac, whole = frac + 256, (whole - step) & 0xFF
    else:
        frac += doubled
        if frac >= 256:
            frac, whole = frac - 256, (whole + step) & 0xFF
    return whole, frac


def lands(seat: int, left: tuple[int, int], right: tuple[int, int], angle: int, power: int) -> bool:
    """Does `seat`'s shell, fired from its tank (`left`, `right`: the tanks' stored (x, y)), pass
    through the other tank's hitbox on its way down? The ROM's flight over flat ground."""
    (x, y), (tx, ty) = ((left[0] + 4, left[1] - 4), right) if seat == 0 else ((right[0] - 5, right[1] - 4), left)
    vel_x, vel_y = _flight_velocity(angle, power)
    frac_x = frac_y = frac_grav = 0
    for _ in range(1000):
        x, frac_x = _twos_add_frac(x, frac_x, vel_x, 1)
        y, frac_y = _twos_add_frac(y, frac_y, vel_y, -1)
        x = 63 if x == 255 else 0 if x == 64 else x
        if y == 31:
            return False
        if y < 32 and abs(x - tx) <= 3 and -2 <= ty - y <= 2 and vel_y & 0x80:
            return True
        frac_grav += 128
        if frac_grav >= 256:
            frac_grav, vel_y = frac_grav - 256, (vel_y - 1) & 0xFF
    return False


def power_for(seat: int, distance: int, dy: int) -> int:
    """How `POWER_TABLE` was made: the middle of the first run of powers below 75 that `lands`."""
    y = 28 - max(0, dy)
    hits = [p for p in range(1, 75) if lands(seat, (7, y), (7 + distance, y + dy), AIM_ANGLE[seat], p)]
    run = hits[:1]
    for p in hits[1:]:
        if p != run[-1] + 1:
            break
        run.append(p)
    return run[len(run) // 2] if run else 0


def _hits(state):
    return jnp.stack([ram_value(state, SCORE[0]), ram_value(state, SCORE[1])])


def _lead(state):
    hits = _hits(state)
    return jnp.stack([hits[0] - hits[1], hits[1] - hits[0]])


def _mover(state):
    return 1 - (ram_value(state, TURN) & 1)


def _over(state):
    return _hits(state).max() >= HITS_TO_WIN


def scripted_policy(state, seat: int):
    """Aim at `AIM_ANGLE[seat]` with `POWER_TABLE`'s power, one key a step, then fire."""
    distance = ram_value(state, PLAYER2_DATA) - ram_value(state, PLAYER1_DATA)
    dy = ram_value(state, PLAYER2_DATA + 1) - ram_value(state, PLAYER1_DATA + 1)
    row = jnp.clip((distance - DISTANCES[0] + 4) // 8, 0, len(DISTANCES) - 1)
    target = jnp.asarray(POWER_TABLE, jnp.int32)[seat, row, jnp.clip(dy + DY_RANGE, 0, 2 * DY_RANGE)]
    angle, power = state.V[ANGLE].astype(jnp.int32), state.V[POWER].astype(jnp.int32)
    aim = AIM_ANGLE[seat]
    action = jnp.where(angle < aim, ANGLE_UP, jnp.where(angle > aim, ANGLE_DOWN,
                       jnp.where(power < target, POWER_UP, jnp.where(power > target, POWER_DOWN, FIRE))))
    return jnp.where(in_routine(state, *AIM), action, 0).astype(jnp.int32)


SPECS = (archive_spec(
    "tank",
    id="TankArchive",
    rom_sha1="3f9ef8dec999574a188ec3b9615cff9888283c85",
    action_keys=KEYS,
    score_fn=lambda state: _lead(state)[0],
    terminated_fn=_over,
    startup=((0, 320),),
    max_episode_steps=4500,
    solo=False,
    seats=Seats(
        action_keys=(KEYS, KEYS),
        score_fn=_lead,
        turn_fn=_mover,
        zero_sum=True,
        names=("left tank", "right tank"),
        scripted_policy=scripted_policy,
    ),
    category="planning",
    description="Two tanks take turns to set angle (keys 7/9) and power (keys 5/8) and fire (key E) "
                "over a random hill; reward +1 for a hit on the other tank and -1 for a hit taken "
                "(zero-sum); the match ends at 3 hits.",
),)
