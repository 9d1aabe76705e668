"""Two tiny two-player games written for the tests, so every number of the multi-agent env tests is
worked by hand (see tests/counter_game.py for the one-player one).

"TwoCounters" (simultaneous): each frame, key 1 adds 1 and key 2 adds 2 to V0 (seat 0), key 4 adds 1
and key 5 adds 2 to V1 (seat 1); then one sprite is drawn, which under the "chip8" profile ends the
frame: holding a seat's first key for a 4-frame step scores it 4. Over when either reaches 24.

"TakeTurns" (turn-based, zero-sum): V6 is the seat to move. On a frame where the mover holds its
key (1 for seat 0, 4 for seat 1) its counter (V0, V1) goes up by 1 and the turn passes; the other
seat's key does nothing. Each seat's score is its counter minus the other's. Over at 5.
"""

import hashlib

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec, Seats

TWO_COUNTERS_ROM = bytes.fromhex(
    "6000" "6100"  # 200: V0 := 0, V1 := 0
    "6201" "6302" "6404" "6505"  # 204: V2..V5 := the keys 1, 2, 4, 5
    "E2A1" "7001"  # 20C: key 1 held: V0 += 1
    "E3A1" "7002"  # 210: key 2 held: V0 += 2
    "E4A1" "7101"  # 214: key 4 held: V1 += 1
    "E5A1" "7102"  # 218: key 5 held: V1 += 2
    "00E0" "A050" "D015"  # 21C: clear, I := glyph 0, draw at (V0, V1): the frame ends
    "120C"  # 222: again
)
TAKE_TURNS_ROM = bytes.fromhex(
    "6000" "6100" "6600"  # 200: V0 := 0, V1 := 0, V6 := 0 (seat 0 to move)
    "6201" "6404"  # 206: V2 := key 1, V4 := key 4
    "3600" "121A"  # 20A: seat 1 to move: jump 21A
    "E2A1" "1214" "1226"  # 20E: key 1 held: jump 214, else to the draw
    "7001" "6601" "1226"  # 214: V0 += 1, seat 1 to move, draw
    "E4A1" "1220" "1226"  # 21A: key 4 held: jump 220, else to the draw
    "7101" "6600" "1226"  # 220: V1 += 1, seat 0 to move, draw
    "00E0" "A050" "D015" "120A"  # 226: clear, glyph 0, draw (the frame ends), again
)
GOAL, TURNS_GOAL = 24, 5


def _counters(state):
    return jnp.stack([state.V[0], state.V[1]]).astype(jnp.int32)


TWO_COUNTERS = GameSpec(
    id="TwoCounters", title="Two counters (test game)", rom_file="two_counters.ch8",
    rom_sha1=hashlib.sha1(TWO_COUNTERS_ROM).hexdigest(), action_keys=(1, 2),
    score_fn=lambda s: s.V[0].astype(jnp.int32), terminated_fn=lambda s: (s.V[0] >= GOAL) | (s.V[1] >= GOAL),
    category="reaction", description="Each seat holds its keys to count up to 24.", max_episode_steps=50,
    startup=((0, 2),),  # the set-up, then the first draw: every step then starts at the loop's top
    seats=Seats(action_keys=((1, 2), (4, 5)), score_fn=_counters,
                scripted_policy=lambda state, seat: jnp.int32(2)),
)
TAKE_TURNS = GameSpec(
    id="TakeTurns", title="Take turns (test game)", rom_file="take_turns.ch8",
    rom_sha1=hashlib.sha1(TAKE_TURNS_ROM).hexdigest(), action_keys=(1,),
    score_fn=lambda s: s.V[0].astype(jnp.int32),
    terminated_fn=lambda s: (s.V[0] >= TURNS_GOAL) | (s.V[1] >= TURNS_GOAL),
    category="planning", description="The seats count in turn.", max_episode_steps=50, solo=False,
    startup=((0, 1),),
    seats=Seats(action_keys=((1,), (4,)), turn_fn=lambda s: s.V[6].astype(jnp.int32),
                score_fn=lambda s: jnp.stack([s.V[0], s.V[1]]).astype(jnp.int32) - jnp.stack([s.V[1], s.V[0]]),
                zero_sum=True),
)
