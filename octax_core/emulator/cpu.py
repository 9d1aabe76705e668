"""Fetch, decode, execute: one instruction as a pure function of the state.

Every handler runs on every instruction (under `vmap` there is no real branching), so handlers
return small effects and `execute` merges them field by field with scalar selects on the decoded
kind, then applies the merged effect once. Whatever the opcode, an instruction costs two
contiguous memory reads (opcode, 16 bytes at I), one 16-byte window write (two, to keep the
mirror), one sprite read and XOR, and a few lane selects on the registers and the stack.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from octax_core.emulator.decode import Kind, decode
from octax_core.emulator.ops import Context, alu, display, flow, keys, memory, timers
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

EFFECT_FIELDS = {
    "pc": "next pc (default pc + 2)",
    "vx": "new value of Vx (default unchanged)",
    "vf": "flag written to VF after vx (default none)",
    "i": "new I (default unchanged)",
    "sp": "new stack pointer (default unchanged)",
    "push": "return address written to stack[sp] (default none)",
    "mem_data": "(16,) bytes to write at I (default: the bytes already there)",
    "mem_count": "how many of mem_data to write (default 0)",
    "load_count": "load V0..V(count-1) from memory at I (default 0)",
    "delay_timer": "new delay timer (default unchanged)",
    "sound_timer": "new sound timer (default unchanged)",
    "rng": "new xorshift32 state (default unchanged)",
    "key_wait": "new FX0A progress (default unchanged)",
    "clear": "clear the screen first (default False)",
}


def _lanes():
    return jnp.arange(16, dtype=jnp.int32)


def _merge(kind, effects: dict, field: str, default):
    """The value of `field` chosen by `kind` among the handlers that set it, else `default`."""
    value = default
    for handler_kind, effect in effects.items():
        if field in effect:
            value = jnp.where(kind == handler_kind, effect[field], value)
    return value


def _writes(kind, effects: dict, field: str):
    """Whether the handler chosen by `kind` sets `field`."""
    kinds = [k for k, effect in effects.items() if field in effect]
    return jnp.isin(kind, jnp.asarray(kinds, jnp.int32))


def _context(quirks: Quirks, state: MachineState, keys, kind_fields, window, collision):
    V = state.V.astype(jnp.int32)
    sp = state.sp.astype(jnp.int32)
    return Context(
        quirks=quirks, x=kind_fields.x, y=kind_fields.y, n=kind_fields.n, nn=kind_fields.nn,
        nnn=kind_fields.nnn, vx=V[kind_fields.x], vy=V[kind_fields.y], v0=V[0],
        pc=state.pc.astype(jnp.int32), I=state.I.astype(jnp.int32), sp=sp,
        stack_top=state.stack[(sp - 1) & 0xF].astype(jnp.int32), V=V, window=window,
        collision=collision, keys=keys, delay_timer=state.delay_timer.astype(jnp.int32),
        rng=state.rng, key_wait=state.key_wait.astype(jnp.int32),
    )


def execute(quirks: Quirks, state: MachineState, keys: jax.Array, stalled=None):
    """Runs the instruction at pc.

    Args:
        quirks: the interpreter behaviour (static).
        state: one machine.
        keys: uint32 mask of held keys.
        stalled: bool; when true the frame is over (display wait) and nothing changes.

    Returns:
        (new state, whether a DXYN ran).
    """
    lanes = _lanes()
    pc, I = state.pc.astype(jnp.int32), state.I.astype(jnp.int32)
    # Contiguous slices thanks to the mirror: the opcode at pc, and 16 bytes at I (FX65 loads
    # and the read half of FX33/FX55's read-modify-write).
    opcode = jax.lax.dynamic_slice(state.memory, (pc + MEMORY_OFFSET,), (2,)).astype(jnp.int32)
    window = jax.lax.dynamic_slice(state.memory, (I + MEMORY_OFFSET,), (16,)).astype(jnp.int32)
    fields = decode(opcode[0], opcode[1])
    kind = fields.kind if stalled is None else jnp.where(stalled, int(Kind.STALL), fields.kind)

    # The memory write goes first and DXYN, the one handler that reads the collision, after it,
    # taking its sprite from the written memory: DXYN writes no memory, so those are the same
    # bytes, and XLA never has to copy the memory buffer to keep the old version alive.
    c = _context(quirks, state, keys, fields, window, collision=jnp.bool_(False))
    effects = {k: handler(c) for k, handler in HANDLERS.items() if k != Kind.DRW}
    unknown = {field for effect in effects.values() for field in effect} - EFFECT_FIELDS.keys()
    if unknown:  # checked while tracing, so it costs nothing per instruction
        raise RuntimeError(f"handlers returned unknown effect fields {sorted(unknown)}")

    def merged(field, default):
        return _merge(kind, effects, field, default)

    mem_count = merged("mem_count", jnp.int32(0))
    written = jnp.where(lanes < mem_count, merged("mem_data", c.window), c.window)
    new_memory = _write_window(state.memory, written.astype(jnp.uint8), I)

    y = c.vy & 31
    aligned = jax.lax.dynamic_slice(new_memory, (I - y + MEMORY_OFFSET,),
                                    (32 if quirks.clipping else 64,))
    mask = display.sprite_mask(aligned.astype(jnp.int32), c.vx & 63, y,
                               jnp.where(kind == Kind.DRW, fields.n, 0), quirks.clipping)
    collision = display.collides(state.screen, mask)
    effects[Kind.DRW] = display.op_dxyn(c._replace(collision=collision))

    # Registers by lane selects, with VF after Vx; a scatter at x would cost more under vmap.
    V = jnp.where(lanes < merged("load_count", jnp.int32(0)), c.window, c.V)
    V = jnp.where(lanes == c.x, merged("vx", c.vx), V)
    V = jnp.where((lanes == 15) & _writes(kind, effects, "vf"), merged("vf", jnp.int32(0)), V)

    keep = jnp.where(merged("clear", jnp.bool_(False)), jnp.uint32(0), jnp.uint32(0xFFFFFFFF))
    pushing = (lanes == c.sp) & _writes(kind, effects, "push")
    new_state = MachineState(
        memory=new_memory,
        V=V.astype(jnp.uint8),
        I=(merged("i", c.I) & 0xFFF).astype(jnp.uint16),
        pc=(merged("pc", c.pc + 2) & 0xFFF).astype(jnp.uint16),
        sp=merged("sp", c.sp).astype(jnp.uint8),
        stack=jnp.where(pushing, merged("push", c.pc) & 0xFFF, state.stack).astype(jnp.uint16),
        delay_timer=merged("delay_timer", c.delay_timer).astype(jnp.uint8),
        sound_timer=merged("sound_timer", state.sound_timer.astype(jnp.int32)).astype(jnp.uint8),
        screen=(state.screen & keep) ^ mask,
        rng=merged("rng", c.rng),
        key_wait=merged("key_wait", c.key_wait).astype(jnp.uint8),
    )
    return new_state, kind == Kind.DRW


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
        state, drew = execute(quirks, state, keys, frame_over if gated else None)
        if quirks.display_wait:  # the VIP's DXYN waits for the next vertical blank
            frame_over = frame_over | drew
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
