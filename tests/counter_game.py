"""A tiny game written for the tests ("Counter"), so every number in the env tests is worked by hand.

V0 is the score. Each frame, key 1 adds 1 and key 2 adds 2, then the screen is cleared and the
digit 0 drawn at (random x, y = V0). Under the "chip8" profile the DXYN ends the frame, so one
loop runs per frame: holding key 1 for a 4-frame step scores 4, key 2 scores 8. The game is over
when V0 >= 24; lives count down to it (24 - V0).
"""

import hashlib

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

COUNTER_ROM = bytes.fromhex(
    "6000"  # 200: V0 := 0
    "6201"  # 202: V2 := 1
    "6302"  # 204: V3 := 2
    "E2A1"  # 206: skip unless key V2 held
    "7001"  # 208: V0 += 1
    "E3A1"  # 20A: skip unless key V3 held
    "7002"  # 20C: V0 += 2
    "C53F"  # 20E: V5 := random & 0x3F
    "00E0"  # 210: clear
    "A050"  # 212: I := glyph 0
    "D505"  # 214: draw at (V5, V0), 5 rows; ends the frame (display wait)
    "1206"  # 216: jump 206
)
GOAL = 24


def _score(state):
    return state.V[0].astype(jnp.int32)


COUNTER = GameSpec(
    id="Counter", title="Counter (test game)", rom_file="counter.ch8",
    rom_sha1=hashlib.sha1(COUNTER_ROM).hexdigest(), action_keys=(1, 2), score_fn=_score,
    terminated_fn=lambda s: s.V[0] >= GOAL, lives_fn=lambda s: jnp.maximum(GOAL - _score(s), 0),
    category="reaction", description="Hold 1 or 2 to count up to 24.", max_episode_steps=50,
)
