"""Instruction handlers, one tiny function per opcode, grouped by family.

A handler takes the `Context` of the instruction being executed and returns an `Effect` that
sets only the fields it changes. Handlers never build a state; `octax_core.emulator.cpu` merges
the effects field by field and applies the result once, so under `vmap` each field pays for a
few scalar selects instead of every handler copying 4 KB of memory.
"""

from __future__ import annotations

from typing import NamedTuple, Optional

import jax

from octax_core.emulator.quirks import Quirks


class Context(NamedTuple):
    """What a handler may read: decoded fields and the registers it needs, as int32 scalars."""

    quirks: Quirks  # static
    x: jax.Array
    y: jax.Array
    n: jax.Array
    nn: jax.Array
    nnn: jax.Array
    vx: jax.Array
    vy: jax.Array
    v0: jax.Array
    pc: jax.Array
    I: jax.Array
    sp: jax.Array
    stack_top: jax.Array  # stack[(sp - 1) mod 16]
    V: jax.Array  # (16,) int32, all registers
    window: jax.Array  # (16,) int32: memory[I .. I + 15], wrapping
    collision: jax.Array  # bool: the sprite of this DXYN would erase a lit pixel
    keys: jax.Array  # uint32 mask of held keys, bit k = key k
    delay_timer: jax.Array
    rng: jax.Array  # uint32
    key_wait: jax.Array
    plane: jax.Array  # the selected planes, 0..3 (CHIP-8 and SUPER-CHIP: always 1)
    # Where a platform has them (None elsewhere, where no handler reads them):
    skip_bytes: Optional[jax.Array] = None  # XO-CHIP: how far a skip jumps, 2, or 4 over F000 NNNN
    next_word: Optional[jax.Array] = None  # XO-CHIP: the 16 bits after the opcode (F000 NNNN's address)
    hires: Optional[jax.Array] = None  # SUPER-CHIP and later: bool
    flags: Optional[jax.Array] = None  # SUPER-CHIP and later: (16,) int32, the flag registers


class Effect(NamedTuple):
    """What one instruction changes. A field left None is one the handler does not touch; the
    merged effect (`octax_core.emulator.cpu.merge`) fills it with the default given here."""

    pc: Optional[jax.Array] = None  # next pc (default pc + 2)
    vx: Optional[jax.Array] = None  # new value of Vx (default unchanged)
    vf: Optional[jax.Array] = None  # flag written to VF after vx (default none)
    i: Optional[jax.Array] = None  # new I (default unchanged)
    sp: Optional[jax.Array] = None  # new stack pointer (default unchanged)
    push: Optional[jax.Array] = None  # return address written to stack[sp] (default none)
    mem_data: Optional[jax.Array] = None  # (16,) bytes to write at I (default: the bytes there)
    mem_count: Optional[jax.Array] = None  # how many of mem_data to write (default 0)
    load_count: Optional[jax.Array] = None  # load V0..V(count-1) from memory at I (default 0), after vx
    delay_timer: Optional[jax.Array] = None  # new delay timer (default unchanged)
    sound_timer: Optional[jax.Array] = None  # new sound timer (default unchanged)
    rng: Optional[jax.Array] = None  # new xorshift32 state (default unchanged)
    key_wait: Optional[jax.Array] = None  # new FX0A progress (default unchanged)
    clear_planes: Optional[jax.Array] = None  # plane mask cleared (default 0; CHIP-8's one plane is 1)
    # SUPER-CHIP and XO-CHIP only; their defaults are None on CHIP-8, and `merge` skips them there:
    load_flags: Optional[jax.Array] = None  # the load_count registers come from the flags, not memory
    v_lanes: Optional[jax.Array] = None  # (16,) bool: registers loaded from v_values (default none)
    v_values: Optional[jax.Array] = None  # (16,) values for the v_lanes (written after vx, before vf)
    scroll_x: Optional[jax.Array] = None  # scroll the selected planes right by this many pixels
    scroll_y: Optional[jax.Array] = None  # ... and down by this many (screen pixels; default 0)
    hires: Optional[jax.Array] = None  # new display mode (default unchanged)
    exited: Optional[jax.Array] = None  # 00FD ran (default False)
    flags: Optional[jax.Array] = None  # (16,) new flag registers (default unchanged)
    plane: Optional[jax.Array] = None  # new plane selection (default unchanged)
    audio_pattern: Optional[jax.Array] = None  # (16,) new audio pattern (default unchanged)
    pitch: Optional[jax.Array] = None  # new pitch (default unchanged)


def next_pc(c: Context, skip) -> jax.Array:
    """The address after this instruction, or after the next one when `skip` holds."""
    step = 2 if c.skip_bytes is None else c.skip_bytes
    return c.pc + 2 + step * skip.astype(c.pc.dtype)
