"""SUPER-CHIP and XO-CHIP instructions: display modes, scrolls, big digits, flags, exit, and
XO-CHIP's long I, register ranges, planes and audio.

Handlers only describe what changes; the screen work (clearing planes, scrolling them, drawing a
sprite) happens once per instruction in `octax_core.emulator.cpu`, driven by the merged
`clear_planes`, `scroll_x`, `scroll_y` and the decoded kind. CLS and DXYN, which every platform
has, are in `display`.
"""

from __future__ import annotations

import jax.numpy as jnp

from octax_core.emulator.ops import Context, Effect
from octax_core.emulator.ops.display import ALL_PLANES
from octax_core.emulator.state import BIG_FONT_ADDRESS


def op_00cn(c: Context) -> Effect:
    """SCD n: scroll the selected planes down n rows."""
    return Effect(scroll_y=c.n)


def op_00dn(c: Context) -> Effect:
    """SCU n (XO-CHIP): scroll the selected planes up n rows."""
    return Effect(scroll_y=-c.n)


def op_00fb(c: Context) -> Effect:
    """SCR: scroll the selected planes right 4 pixels."""
    return Effect(scroll_x=jnp.int32(4))


def op_00fc(c: Context) -> Effect:
    """SCL: scroll the selected planes left 4 pixels."""
    return Effect(scroll_x=jnp.int32(-4))


def op_00fd(c: Context) -> Effect:
    """EXIT: the program ends; pc stays on the 00FD and the machine stands still from now on."""
    return Effect(pc=c.pc, exited=jnp.bool_(True))


def op_00fe(c: Context) -> Effect:
    """LOW: 64x32 mode; every plane is cleared."""
    return Effect(hires=jnp.bool_(False), clear_planes=jnp.int32(ALL_PLANES))


def op_00ff(c: Context) -> Effect:
    """HIGH: 128x64 mode; every plane is cleared."""
    return Effect(hires=jnp.bool_(True), clear_planes=jnp.int32(ALL_PLANES))


def op_fx30(c: Context) -> Effect:
    """LD HF, Vx: I = address of the big (8x10) digit for the low nibble of Vx."""
    return Effect(i=BIG_FONT_ADDRESS + 10 * (c.vx & 0xF))


def op_fx75(c: Context) -> Effect:
    """LD R, Vx: flags[0..x] = V0..Vx."""
    lanes = jnp.arange(16, dtype=jnp.int32)
    return Effect(flags=jnp.where(lanes <= c.x, c.V, c.flags))


def op_fx85(c: Context) -> Effect:
    """LD Vx, R: V0..Vx = flags[0..x]."""
    return Effect(load_count=c.x + 1, load_flags=jnp.bool_(True))


def _range(c: Context):
    """5XY2/5XY3's registers: lane r is in the range when it lies between x and y (either order),
    and its byte is at I + |r - x|."""
    lanes = jnp.arange(16, dtype=jnp.int32)
    in_range = (lanes >= jnp.minimum(c.x, c.y)) & (lanes <= jnp.maximum(c.x, c.y))
    return lanes, in_range


def op_5xy2(c: Context) -> Effect:
    """SAVE Vx..Vy: memory[I + k] = V[x +/- k]; I does not move."""
    lanes, _ = _range(c)
    step = jnp.where(c.x <= c.y, 1, -1)
    register = (c.x + step * lanes) & 0xF  # byte k holds V[x + k] (or V[x - k] when y < x)
    return Effect(mem_data=c.V[register], mem_count=jnp.abs(c.y - c.x) + 1)


def op_5xy3(c: Context) -> Effect:
    """LOAD Vx..Vy: V[x +/- k] = memory[I + k]; I does not move."""
    lanes, in_range = _range(c)
    # lane r reads byte |r - x|: chosen among the 16 by selects, not gathered (a gather inside the
    # fused register update keeps XLA:CPU from vectorising that kernel; measured: docs/machine-log.md)
    distance = jnp.abs(lanes - c.x)
    values = c.window[0]
    for k in range(1, 16):
        values = jnp.where(distance == k, c.window[k], values)
    return Effect(v_lanes=in_range, v_values=values)


def op_f000(c: Context) -> Effect:
    """LD I, NNNN (XO-CHIP): I = the next 16-bit word; the instruction is 4 bytes long."""
    return Effect(i=c.next_word, pc=c.pc + 4)


def op_fn01(c: Context) -> Effect:
    """PLANE n (XO-CHIP): select the planes that drawing, clearing and scrolling act on."""
    return Effect(plane=c.x)


def op_f002(c: Context) -> Effect:
    """AUDIO (XO-CHIP): load the 16-byte audio pattern from memory at I."""
    return Effect(audio_pattern=c.window)


def op_fx3a(c: Context) -> Effect:
    """PITCH Vx (XO-CHIP): set the audio pattern's playback pitch."""
    return Effect(pitch=c.vx)
