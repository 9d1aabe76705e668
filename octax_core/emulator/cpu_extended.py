"""Fetch, decode, execute and the frame for SUPER-CHIP and XO-CHIP (CHIP-8's are `cpu`).

The same design as `cpu`: every handler runs, effects merge field by field, the result applies
once. What differs is kept here so that the CHIP-8 program never sees it: a 4-byte fetch (XO-CHIP's
F000 NNNN, and skips that jump over it), addresses that wrap at the platform's memory size, the
128x64 bit planes (clear, scroll and draw act on the selected planes), the flag registers, and
00FD, after which the machine stands still.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from octax_core.emulator import cpu
from octax_core.emulator.decode import Kind, decode
from octax_core.emulator.ops import Context, Effect, extended, planes
from octax_core.emulator.platforms import Platform
from octax_core.emulator.quirks import Quirks
from octax_core.emulator.state import EXTENDED_MIRRORED, MEMORY_OFFSET, MachineState

SPRITE_BYTES = 32  # a 16x16 sprite

_REPLACED = (Kind.CLS, Kind.DRW)
SCHIP_HANDLERS = {
    **{kind: handler for kind, handler in cpu.HANDLERS.items() if kind not in _REPLACED},
    Kind.CLS: extended.op_00e0,
    Kind.SCROLL_DOWN: extended.op_00cn,
    Kind.SCROLL_RIGHT: extended.op_00fb,
    Kind.SCROLL_LEFT: extended.op_00fc,
    Kind.EXIT: extended.op_00fd,
    Kind.LORES: extended.op_00fe,
    Kind.HIRES: extended.op_00ff,
    Kind.LD_BIG_FONT: extended.op_fx30,
    Kind.SAVE_FLAGS: extended.op_fx75,
    Kind.LOAD_FLAGS: extended.op_fx85,
}
XOCHIP_HANDLERS = {
    **SCHIP_HANDLERS,
    Kind.SCROLL_UP: extended.op_00dn,
    Kind.SAVE_RANGE: extended.op_5xy2,
    Kind.LOAD_RANGE: extended.op_5xy3,
    Kind.LD_I_LONG: extended.op_f000,
    Kind.PLANE: extended.op_fn01,
    Kind.AUDIO: extended.op_f002,
    Kind.PITCH: extended.op_fx3a,
}  # DXYN is added per instruction, once its collision is known


def handlers(platform: Platform) -> dict:
    """The handlers of `platform` (both tables list every kind its decoder can produce)."""
    return XOCHIP_HANDLERS if platform.planes > 1 else SCHIP_HANDLERS


def fetch(platform: Platform, quirks: Quirks, state: MachineState, keys, stalled) -> cpu.Fetched:
    """Reads 4 bytes at pc (the opcode and the word after it) and 16 at I, decodes, and builds
    the context, with the extended fields (skip length, the next word, mode, flags, planes)."""
    pc, I = state.pc.astype(jnp.int32), state.I.astype(jnp.int32)
    code = jax.lax.dynamic_slice(state.memory, (pc + MEMORY_OFFSET,), (4,)).astype(jnp.int32)
    window = jax.lax.dynamic_slice(state.memory, (I + MEMORY_OFFSET,), (16,)).astype(jnp.int32)
    fields = decode(code[0], code[1], platform.name)
    kind = jnp.where(stalled, int(Kind.STALL), fields.kind)
    next_word = (code[2] << 8) | code[3]
    xochip = platform.planes > 1
    context = cpu.context(quirks, state, fields, pc, I, window, keys)._replace(
        # A skip jumps over a whole instruction: 4 bytes when it is XO-CHIP's F000 NNNN.
        skip_bytes=jnp.where(next_word == 0xF000, 4, 2) if xochip else None,
        next_word=next_word, hires=state.hires, flags=state.flags.astype(jnp.int32),
        plane=state.plane.astype(jnp.int32) if xochip else jnp.int32(1),
    )
    return cpu.Fetched(fields, kind, context)


def _defaults(state: MachineState, c: Context) -> Effect:
    """What an instruction leaves alone, extended fields included (None where the platform has none)."""
    xochip = state.plane is not None
    return cpu._defaults(state, c)._replace(
        v_lanes=jnp.zeros(16, jnp.bool_), v_values=c.V, clear_planes=jnp.int32(0), scroll_x=jnp.int32(0),
        scroll_y=jnp.int32(0), hires=c.hires, exited=state.exited, flags=c.flags,
        plane=c.plane if xochip else None,
        audio_pattern=state.audio_pattern.astype(jnp.int32) if xochip else None,
        pitch=state.pitch.astype(jnp.int32) if xochip else None,
    )


def execute(platform: Platform, quirks: Quirks, state: MachineState, keys, stalled):
    """Runs the instruction at pc (see `cpu.execute`); returns (new state, the `Kind` that ran)."""
    fetched = fetch(platform, quirks, state, keys, stalled)
    kind, c = fetched.kind, fetched.context
    table = handlers(platform)
    effects = {k: handler(c) for k, handler in table.items()}
    defaults = _defaults(state, c)
    memory = _write_memory(platform, state.memory, cpu.merge(kind, effects, defaults), c)
    # As on CHIP-8, the sprite is read from the written memory: DXYN writes none, so these are
    # its bytes, and the old memory buffer need not stay alive.
    drawing = kind == Kind.DRW
    mask = planes.sprite_mask(_sprite_bytes(platform, memory, c), c.vx, c.vy, fetched.fields.n, c.hires, c.plane,
                              platform.planes, quirks.clipping, drawing)
    effects[Kind.DRW] = extended.op_dxyn(c._replace(collision=planes.collides(state.screen, mask)))
    effect = cpu.merge(kind, effects, defaults)
    return _apply(platform, state, kind, effects, effect, memory, mask, c), kind


def _sprite_bytes(platform: Platform, memory, c: Context):
    """(planes, 32) int32: each plane's sprite bytes. Plane 1's start at I; plane 2's follow
    plane 1's rows when both planes are selected, else they start at I too."""
    first = jax.lax.dynamic_slice(memory, (c.I + MEMORY_OFFSET,), (SPRITE_BYTES,))
    if platform.planes == 1:
        return first[None, :].astype(jnp.int32)
    wide = c.n == 0
    size = jnp.where(wide, 32, c.n) * (c.plane & 1)  # plane 1's bytes, when plane 1 is drawn
    second = jax.lax.dynamic_slice(memory, (c.I + size + MEMORY_OFFSET,), (SPRITE_BYTES,))
    return jnp.stack([first, second]).astype(jnp.int32)


def _write_memory(platform: Platform, memory, effect: Effect, c: Context):
    """The merged effect's memory write: its first mem_count bytes at I, the rest unchanged."""
    lanes = jnp.arange(16, dtype=jnp.int32)
    written = jnp.where(lanes < effect.mem_count, effect.mem_data, c.window).astype(jnp.uint8)
    return write_window(platform, memory, written, c.I)


def write_window(platform: Platform, memory, window, I):
    """Writes 16 bytes at address I, wrapping at the memory size, and keeps the 64 mirrored
    bytes after RAM in step (`state.EXTENDED_MIRRORED`; see `cpu._write_window`)."""
    size = platform.memory_size
    memory = jax.lax.dynamic_update_slice(memory, window, (I + MEMORY_OFFSET,))
    other = jnp.where(I > size - 16, I - size, jnp.where(I < EXTENDED_MIRRORED, I + size, I))
    return jax.lax.dynamic_update_slice(memory, window, (other + MEMORY_OFFSET,))


def _apply(platform: Platform, state: MachineState, kind, effects: dict, effect: Effect, memory, mask,
           c: Context) -> MachineState:
    """The merged effect applied once (see `cpu._apply`); then the planes: clear, scroll, draw."""
    lanes = jnp.arange(16, dtype=jnp.int32)
    V = jnp.where(lanes < effect.load_count, c.window, c.V)
    V = jnp.where(effect.v_lanes, effect.v_values, V)
    V = jnp.where(lanes == c.x, effect.vx, V)
    V = jnp.where((lanes == 15) & cpu.sets(kind, effects, "vf"), effect.vf, V)
    pushing = (lanes == c.sp) & cpu.sets(kind, effects, "push")
    address_mask = platform.memory_size - 1

    plane_index = jnp.arange(platform.planes, dtype=jnp.int32)[:, None, None]
    cleared = ((effect.clear_planes >> plane_index) & 1) == 1
    screen = jnp.where(cleared, jnp.uint32(0), state.screen)
    scale = jnp.where(c.hires, 1, 2)  # a lores scroll moves lores pixels: 2 grid pixels each
    scrolled = planes.scroll(screen, effect.scroll_x * scale, effect.scroll_y * scale)
    screen = jnp.where(((c.plane >> plane_index) & 1) == 1, scrolled, screen) ^ mask

    xochip = {}
    if platform.planes > 1:
        xochip = dict(plane=effect.plane.astype(jnp.uint8), audio_pattern=effect.audio_pattern.astype(jnp.uint8),
                      pitch=effect.pitch.astype(jnp.uint8))
    return MachineState(
        memory=memory,
        V=V.astype(jnp.uint8),
        I=(effect.i & address_mask).astype(jnp.uint16),
        pc=(effect.pc & address_mask).astype(jnp.uint16),
        sp=effect.sp.astype(jnp.uint8),
        stack=jnp.where(pushing, effect.push & address_mask, state.stack).astype(jnp.uint16),
        delay_timer=effect.delay_timer.astype(jnp.uint8),
        sound_timer=effect.sound_timer.astype(jnp.uint8),
        screen=screen,
        rng=effect.rng,
        key_wait=effect.key_wait.astype(jnp.uint8),
        hires=effect.hires,
        flags=effect.flags.astype(jnp.uint8),
        exited=effect.exited,
        **xochip,
    )


def run_frame(platform: Platform, quirks: Quirks, instructions_per_frame: int, state: MachineState, keys,
              halted=None) -> MachineState:
    """One 60 Hz frame (see `cpu.run_frame`). A frame that starts after 00FD does nothing, its
    timers included; the frame of the 00FD stops there and ticks its timers."""

    def instruction(carry, _):
        state, frame_over = carry
        state, kind = execute(platform, quirks, state, keys, frame_over)
        if quirks.display_wait:
            frame_over = frame_over | (kind == Kind.DRW)
        return (state, frame_over | state.exited), None

    still = state.exited if halted is None else state.exited | halted
    (ran, _), _ = jax.lax.scan(instruction, (state, still), None, length=instructions_per_frame)
    ticked = cpu.tick_timers(ran)
    return ran.replace(delay_timer=jnp.where(still, ran.delay_timer, ticked.delay_timer),
                       sound_timer=jnp.where(still, ran.sound_timer, ticked.sound_timer))
