"""Fetch, decode, execute: one instruction as a pure function of the state.

Every handler runs on every instruction (under `vmap` there is no real branching), so handlers
return small effects and `execute` merges them field by field with scalar selects on the decoded
kind, then applies the merged effect once. Whatever the opcode, an instruction costs two
contiguous memory reads (opcode, 16 bytes at I), one 16-byte window write (two, to keep the
mirror), one sprite read and XOR, and a few lane selects on the registers and the stack.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from octax_core.emulator.decode import Decoded, Kind, decode
from octax_core.emulator.ops import Context, Effect, alu, display, flow, keys, memory, timers
from octax_core.emulator.quirks import Quirks
from octax_core.emulator.rom import MEMORY_SIZE
from octax_core.emulator.state import MEMORY_OFFSET, MachineState

HANDLERS = {
    Kind.STALL: flow.op_stall,
    Kind.CLS: display.op_00e0,
    Kind.RET: flow.op_00ee,
    Kind.JP: flow.op_1nnn,
    Kind.CALL: flow.op_2nnn,
    Kind.SE_NN: flow.op_3xnn,
    Kind.SNE_NN: flow.op_4xnn,
    Kind.SE_XY: flow.op_5xy0,
    Kind.LD_NN: alu.op_6xnn,
    Kind.ADD_NN: alu.op_7xnn,
    Kind.LD_XY: alu.op_8xy0,
    Kind.OR: alu.op_8xy1,
    Kind.AND: alu.op_8xy2,
    Kind.XOR: alu.op_8xy3,
    Kind.ADD_XY: alu.op_8xy4,
    Kind.SUB: alu.op_8xy5,
    Kind.SHR: alu.op_8xy6,
    Kind.SUBN: alu.op_8xy7,
    Kind.SHL: alu.op_8xye,
    Kind.SNE_XY: flow.op_9xy0,
    Kind.LD_I: memory.op_annn,
    Kind.JP_V: flow.op_bnnn,
    Kind.RND: alu.op_cxnn,
    Kind.DRW: display.op_dxyn,
    Kind.SKP: keys.op_ex9e,
    Kind.SKNP: keys.op_exa1,
    Kind.LD_VX_DT: timers.op_fx07,
    Kind.LD_KEY: keys.op_fx0a,
    Kind.LD_DT: timers.op_fx15,
    Kind.LD_ST: timers.op_fx18,
    Kind.ADD_I: memory.op_fx1e,
    Kind.LD_FONT: memory.op_fx29,
    Kind.BCD: memory.op_fx33,
    Kind.STORE: memory.op_fx55,
    Kind.LOAD: memory.op_fx65,
}  # Kind.NOP has no handler: every field keeps its default

class Fetched(NamedTuple):
    """The instruction at pc, decoded, and the context its handler reads."""

    fields: Decoded
    kind: jax.Array  # int32 Kind; STALL while the frame is over (display wait)
    context: Context


def fetch(quirks: Quirks, state: MachineState, keys: jax.Array, stalled=None) -> Fetched:
    """Reads the opcode at pc and the 16 bytes at I, decodes, and builds the handlers' context.

    Both reads are contiguous slices thanks to the RAM mirror (`state.MEMORY_OFFSET`): the
    window at I serves FX65's loads and the read half of FX33/FX55's read-modify-write.
    """
    pc, I = state.pc.astype(jnp.int32), state.I.astype(jnp.int32)
    opcode = jax.lax.dynamic_slice(state.memory, (pc + MEMORY_OFFSET,), (2,)).astype(jnp.int32)
    window = jax.lax.dynamic_slice(state.memory, (I + MEMORY_OFFSET,), (16,)).astype(jnp.int32)
    fields = decode(opcode[0], opcode[1])
    kind = fields.kind if stalled is None else jnp.where(stalled, int(Kind.STALL), fields.kind)
    return Fetched(fields, kind, context(quirks, state, fields, pc, I, window, keys))


def context(quirks: Quirks, state: MachineState, fields: Decoded, pc, I, window, keys) -> Context:
    """The handlers' context of every platform: the decoded fields and the registers, as int32."""
    V, sp = state.V.astype(jnp.int32), state.sp.astype(jnp.int32)
    return Context(
        quirks=quirks, x=fields.x, y=fields.y, n=fields.n, nn=fields.nn, nnn=fields.nnn, vx=V[fields.x],
        vy=V[fields.y], v0=V[0], pc=pc, I=I, sp=sp, stack_top=state.stack[(sp - 1) & 0xF].astype(jnp.int32),
        V=V, window=window, collision=jnp.bool_(False), keys=keys,
        delay_timer=state.delay_timer.astype(jnp.int32), rng=state.rng, key_wait=state.key_wait.astype(jnp.int32),
    )


def merge(kind, effects: dict, defaults: Effect) -> Effect:
    """One effect: each field the value of the handler `kind` selects, where that handler sets
    it, else the field of `defaults`. A chain of scalar selects per field, no branching."""
    merged = {}
    for field, default in zip(Effect._fields, defaults):
        if default is None:  # a field this platform does not have (SUPER-CHIP's, on CHIP-8)
            merged[field] = None
            continue
        value = default
        for handler_kind, effect in effects.items():
            if getattr(effect, field) is not None:
                value = jnp.where(kind == handler_kind, getattr(effect, field), value)
        merged[field] = value
    return Effect(**merged)


def sets(kind, effects: dict, field: str) -> jax.Array:
    """Whether the handler `kind` selects sets `field` (for fields with no neutral default)."""
    kinds = [k for k, effect in effects.items() if getattr(effect, field) is not None]
    return jnp.isin(kind, jnp.asarray(kinds, jnp.int32))


def _defaults(state: MachineState, c: Context) -> Effect:
    """What an instruction leaves alone: pc moves on by 2, everything else stays as it is."""
    return Effect(pc=c.pc + 2, vx=c.vx, vf=jnp.int32(0), i=c.I, sp=c.sp, push=c.pc, mem_data=c.window,
                  mem_count=jnp.int32(0), load_count=jnp.int32(0), delay_timer=c.delay_timer,
                  sound_timer=state.sound_timer.astype(jnp.int32), rng=c.rng, key_wait=c.key_wait,
                  clear=jnp.bool_(False))


def execute(quirks: Quirks, state: MachineState, keys: jax.Array, stalled=None):
    """Runs the instruction at pc: fetch and decode, every handler, merge, apply.

    Args:
        quirks: the interpreter behaviour (static).
        state: one machine.
        keys: uint32 mask of held keys.
        stalled: bool; when true the frame is over (display wait) and nothing changes.

    Returns:
        (new state, the int32 `Kind` that ran: STALL while stalled; `idle` reads it to know
        whether the instruction wrote memory or the screen).
    """
    fetched = fetch(quirks, state, keys, stalled)
    kind, c = fetched.kind, fetched.context
    # The memory write goes first and DXYN, the one handler that reads the collision, after it,
    # taking its sprite from the written memory: DXYN writes no memory, so those are the same
    # bytes, and XLA never has to copy the memory buffer to keep the old version alive.
    effects = {k: handler(c) for k, handler in HANDLERS.items() if k != Kind.DRW}
    defaults = _defaults(state, c)
    memory = _write_memory(state.memory, merge(kind, effects, defaults), c)
    sprite = _sprite_mask(quirks, memory, c, jnp.where(kind == Kind.DRW, fetched.fields.n, 0))
    effects[Kind.DRW] = display.op_dxyn(c._replace(collision=display.collides(state.screen, sprite)))
    new_state = _apply(state, kind, effects, merge(kind, effects, defaults), memory, sprite, c)
    return new_state, kind


def _write_memory(memory, effect: Effect, c: Context):
    """The merged effect's memory write: its first mem_count bytes at I, the rest unchanged."""
    lanes = jnp.arange(16, dtype=jnp.int32)
    written = jnp.where(lanes < effect.mem_count, effect.mem_data, c.window)
    return _write_window(memory, written.astype(jnp.uint8), c.I)


def _sprite_mask(quirks: Quirks, memory, c: Context, height):
    """The XOR mask of the sprite a DXYN draws (all zero for any other instruction: height 0)."""
    y = c.vy & 31
    aligned = jax.lax.dynamic_slice(memory, (c.I - y + MEMORY_OFFSET,), (32 if quirks.clipping else 64,))
    return display.sprite_mask(aligned.astype(jnp.int32), c.vx & 63, y, height, quirks.clipping)


def _apply(state: MachineState, kind, effects: dict, effect: Effect, memory, sprite, c: Context) -> MachineState:
    """The merged effect applied once: registers by lane selects with VF after Vx (a scatter at
    x would cost more under vmap), the stack push, I, pc, timers, the screen."""
    lanes = jnp.arange(16, dtype=jnp.int32)
    V = jnp.where(lanes < effect.load_count, c.window, c.V)
    V = jnp.where(lanes == c.x, effect.vx, V)
    V = jnp.where((lanes == 15) & sets(kind, effects, "vf"), effect.vf, V)
    keep = jnp.where(effect.clear, jnp.uint32(0), jnp.uint32(0xFFFFFFFF))
    pushing = (lanes == c.sp) & sets(kind, effects, "push")
    return MachineState(
        memory=memory,
        V=V.astype(jnp.uint8),
        I=(effect.i & 0xFFF).astype(jnp.uint16),
        pc=(effect.pc & 0xFFF).astype(jnp.uint16),
        sp=effect.sp.astype(jnp.uint8),
        stack=jnp.where(pushing, effect.push & 0xFFF, state.stack).astype(jnp.uint16),
        delay_timer=effect.delay_timer.astype(jnp.uint8),
        sound_timer=effect.sound_timer.astype(jnp.uint8),
        screen=(state.screen & keep) ^ sprite,
        rng=effect.rng,
        key_wait=effect.key_wait.astype(jnp.uint8),
    )


def _write_window(memory, window, I):
    """Writes 16 bytes at address I, wrapping at 4 KiB, and keeps the RAM mirror in step.

    The second write repeats the same bytes one RAM-length away when the window touches the
    mirrored start of RAM (I < 16) or runs past its end (I > 4080, the wrapped bytes land in
    RAM 0x000..); otherwise it rewrites the first window in place. Nothing reads memory after
    these writes, so XLA updates the buffer in place.
    """
    memory = jax.lax.dynamic_update_slice(memory, window, (I + MEMORY_OFFSET,))
    other = jnp.where(I > MEMORY_SIZE - 16, I - MEMORY_SIZE, jnp.where(I < 16, I + MEMORY_SIZE, I))
    return jax.lax.dynamic_update_slice(memory, window, (other + MEMORY_OFFSET,))


def tick_timers(state: MachineState) -> MachineState:
    """The 60 Hz tick: each nonzero timer drops by one."""
    def tick(timer):
        return jnp.where(timer > 0, timer - 1, timer).astype(timer.dtype)
    return state.replace(delay_timer=tick(state.delay_timer), sound_timer=tick(state.sound_timer))


def run_frame(quirks: Quirks, instructions_per_frame: int, state: MachineState, keys,
              halted=None) -> MachineState:
    """One 60 Hz frame: up to `instructions_per_frame` instructions, then the timer tick.

    `halted` (bool, optional) freezes the machine for the frame: no instruction runs and the
    timers do not tick, so the state comes back unchanged (the env uses it for ended episodes).
    """
    gated = quirks.display_wait or halted is not None

    def instruction(carry, _):
        state, frame_over = carry
        state, kind = execute(quirks, state, keys, frame_over if gated else None)
        if quirks.display_wait:  # the VIP's DXYN waits for the next vertical blank
            frame_over = frame_over | (kind == Kind.DRW)
        return (state, frame_over), None

    # Built from the state so that it is batched / sharded like the state (shard_map, vmap).
    frame_over = jnp.zeros_like(state.key_wait, dtype=jnp.bool_)
    if halted is not None:
        frame_over = frame_over | halted
    (state, _), _ = jax.lax.scan(instruction, (state, frame_over), None,
                                 length=instructions_per_frame)
    ticked = tick_timers(state)
    if halted is None:
        return ticked
    return state.replace(delay_timer=jnp.where(halted, state.delay_timer, ticked.delay_timer),
                         sound_timer=jnp.where(halted, state.sound_timer, ticked.sound_timer))
