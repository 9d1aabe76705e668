"""A test game that counts frames ("Ticker"), so a start state tells how many frames it has run.

V1 counts frames: each frame adds 1, then a DXYN ends the frame (display wait under "chip8").
V5 takes a CXNN draw every frame, so the random seed shows. The start-up runs 3 frames, so an
episode that starts after k no-op steps of F frames starts with V1 = 3 + k * F.
"""

import hashlib

import jax.numpy as jnp

from octax_core.env.games.spec import GameSpec

TICKER_ROM = bytes.fromhex(
    "6100"  # 200: V1 := 0
    "7101"  # 202: V1 += 1
    "C5FF"  # 204: V5 := random byte
    "A050"  # 206: I := glyph 0
    "D005"  # 208: draw at (V0, V0); ends the frame
    "1202"  # 20A: jump 202
)
STARTUP_FRAMES = 3

TICKER = GameSpec(
    id="Ticker", title="Ticker (test game)", rom_file="ticker.ch8", rom_sha1=hashlib.sha1(TICKER_ROM).hexdigest(),
    action_keys=(1,), score_fn=lambda s: s.V[1].astype(jnp.int32), terminated_fn=lambda s: jnp.bool_(False),
    startup=((0, STARTUP_FRAMES),), category="reaction", description="Counts frames.",
)

