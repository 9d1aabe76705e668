"""The machine state pytree, boot image, and host-side views of a state.

Everything a running program can change is here, as arrays with explicit dtypes; nothing that
configures the machine is (that lives in `Machine`). The screen is packed, 32 rows of two uint32
words, because a sprite draw is then a shift, an AND and an XOR over a few words.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.rom import MEMORY_SIZE, PROGRAM_ADDRESS, Rom

FONT_ADDRESS = 0x50
FONT = bytes([
    0xF0, 0x90, 0x90, 0x90, 0xF0,  # 0
    0x20, 0x60, 0x20, 0x20, 0x70,  # 1
    0xF0, 0x10, 0xF0, 0x80, 0xF0,  # 2
    0xF0, 0x10, 0xF0, 0x10, 0xF0,  # 3
    0x90, 0x90, 0xF0, 0x10, 0x10,  # 4
    0xF0, 0x80, 0xF0, 0x10, 0xF0,  # 5
    0xF0, 0x80, 0xF0, 0x90, 0xF0,  # 6
    0xF0, 0x10, 0x20, 0x40, 0x40,  # 7
    0xF0, 0x90, 0xF0, 0x90, 0xF0,  # 8
    0xF0, 0x90, 0xF0, 0x10, 0xF0,  # 9
    0xF0, 0x90, 0xF0, 0x90, 0x90,  # A
    0xE0, 0x90, 0xE0, 0x90, 0xE0,  # B
    0xF0, 0x80, 0x80, 0x80, 0xF0,  # C
    0xE0, 0x90, 0x90, 0x90, 0xE0,  # D
    0xF0, 0x80, 0xF0, 0x80, 0xF0,  # E
    0xF0, 0x80, 0xF0, 0x80, 0x80,  # F
])
SCREEN_HEIGHT, SCREEN_WIDTH = 32, 64
NO_KEY = 0xFF  # `key_wait` value while FX0A has not seen a key yet
# Stored memory layout: [32 scratch bytes | the 4 KiB of RAM | 64-byte tail whose first 16 bytes
# always copy RAM 0x000..0x00F]. Address a lives at index a + MEMORY_OFFSET. With the copy, every
# 16-byte window at I and the 2-byte fetch at pc are contiguous dynamic slices (no wrap, no
# gather), every write is two 16-byte window writes (`octax_core.emulator.cpu._write_window`), and a
# sprite's bytes can be read already aligned to screen rows, starting at I - y (scratch and the
# rest of the tail are read only for rows the sprite does not cover).
MEMORY_OFFSET = 32
MIRROR_SIZE = 64
STORED_MEMORY_SIZE = MEMORY_OFFSET + MEMORY_SIZE + MIRROR_SIZE


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class MachineState:
    """One CHIP-8 machine's mutable state (add leading axes to batch it)."""

    memory: jax.Array  # (4192,) uint8: scratch, RAM, mirror (see MEMORY_OFFSET)
    V: jax.Array  # (16,) uint8, registers V0..VF
    I: jax.Array  # () uint16, always < 0x1000
    pc: jax.Array  # () uint16, always < 0x1000
    sp: jax.Array  # () uint8, 0..15
    stack: jax.Array  # (16,) uint16
    delay_timer: jax.Array  # () uint8
    sound_timer: jax.Array  # () uint8
    screen: jax.Array  # (32, 2) uint32; row y, word x // 32, bit 31 - x % 32
    rng: jax.Array  # () uint32, xorshift32 state, never 0
    key_wait: jax.Array  # () uint8, FX0A: NO_KEY or the key seen pressed

    def replace(self, **changes) -> "MachineState":
        return dataclasses.replace(self, **changes)


def boot_memory(rom: Rom) -> np.ndarray:
    """The stored memory at power-on: font at 0x50, program at 0x200, then the mirror."""
    ram = np.zeros(MEMORY_SIZE, np.uint8)
    ram[FONT_ADDRESS : FONT_ADDRESS + len(FONT)] = np.frombuffer(FONT, np.uint8)
    ram[PROGRAM_ADDRESS : PROGRAM_ADDRESS + len(rom.data)] = np.frombuffer(rom.data, np.uint8)
    return stored_memory(ram)


def stored_memory(ram):
    """4 KiB of RAM (numpy or JAX, leading axes allowed) -> the stored layout."""
    xp = np if isinstance(ram, np.ndarray) else jnp
    head = xp.zeros((*ram.shape[:-1], MEMORY_OFFSET), ram.dtype)
    return xp.concatenate([head, ram, ram[..., :MIRROR_SIZE]], axis=-1)


def ram_view(memory):
    """The 4 KiB of RAM inside the stored layout."""
    return memory[..., MEMORY_OFFSET : MEMORY_OFFSET + MEMORY_SIZE]


def seed_rng(key: jax.Array) -> jax.Array:
    """A nonzero xorshift32 state drawn from a JAX key (zero is xorshift's fixed point)."""
    bits = jax.random.bits(key, dtype=jnp.uint32)
    return jnp.where(bits == 0, jnp.uint32(0x9E3779B9), bits)


def boot_state(rom: Rom, key: jax.Array) -> MachineState:
    """A freshly powered-on machine with `rom` loaded; jittable and vmappable over `key`."""
    return MachineState(
        memory=jnp.asarray(boot_memory(rom)),
        V=jnp.zeros(16, jnp.uint8),
        I=jnp.uint16(0),
        pc=jnp.uint16(PROGRAM_ADDRESS),
        sp=jnp.uint8(0),
        stack=jnp.zeros(16, jnp.uint16),
        delay_timer=jnp.uint8(0),
        sound_timer=jnp.uint8(0),
        screen=jnp.zeros((SCREEN_HEIGHT, 2), jnp.uint32),
        rng=seed_rng(key),
        key_wait=jnp.uint8(NO_KEY),
    )


def unpack_screen(screen, on=True, dtype=jnp.bool_):
    """(..., 32, 2) packed words -> (..., 32, 64) pixels, row 0 at the top; numpy in, numpy out.

    Lit pixels read `on` in `dtype` (bool True by default; the env asks for uint8 1 or 255
    directly, so that no bool array is made and converted on the way). The same function serves
    the jitted env (JAX arrays) and host-side rendering (numpy arrays).

    Pixel x of a word is its bit 31 - x, taken as `(word << x) >> 31` rather than
    `(word >> (31 - x)) & 1`: the lane index x is a bare iota, which XLA keeps inside the fused
    loop as a constant vector. `31 - x` is arithmetic on an iota, which XLA's loop-invariant code
    motion hoists out of a `lax.scan` body; the fused unpack then reads the shifts from memory and
    XLA:CPU compiles it to a scalar loop, measured 5x slower on its own (the env scan of
    benchmarks/env_loop.py ran at 0.53x of the bare machine instead of 0.85x).
    """
    xp = np if isinstance(screen, np.ndarray) else jnp
    lanes = xp.arange(32, dtype=xp.uint32)
    bits = (xp.asarray(screen, xp.uint32)[..., None] << lanes) >> xp.uint32(31)
    bits = bits.astype(dtype)
    if dtype != jnp.bool_ and on != 1:
        bits = bits * xp.asarray(on, dtype)
    return bits.reshape(*screen.shape[:-1], SCREEN_WIDTH)


def snapshot(state: MachineState) -> dict[str, np.ndarray]:
    """The state as a dict of numpy arrays, with the screen unpacked to (32, 64) bool.

    Leading batch axes are kept. Meant for tests, debugging and tools; it syncs with the device.
    """
    view = {field.name: np.asarray(getattr(state, field.name)) for field in dataclasses.fields(state)}
    view["memory"] = ram_view(view["memory"])
    view["screen"] = np.asarray(unpack_screen(state.screen))
    return view


def poke(state: MachineState, address: int, data) -> MachineState:
    """Writes `data` (bytes or uint8 array) to memory at `address`, wrapping at 4 KiB.

    Used to set up a program before it runs, e.g. the quirks test ROM's mode byte at 0x1FF.
    """
    values = jnp.asarray(np.frombuffer(bytes(data), np.uint8) if isinstance(data, (bytes, bytearray)) else data, jnp.uint8)
    addresses = (address + np.arange(values.shape[-1])) % MEMORY_SIZE
    ram = ram_view(state.memory).at[..., addresses].set(values)
    return state.replace(memory=stored_memory(ram))


def render_text(state: MachineState, on: str = "#", off: str = ".") -> str:
    """The screen of one machine as 32 lines of 64 characters."""
    pixels = snapshot(state)["screen"]
    if pixels.ndim != 2:
        raise ValueError(f"render_text takes one machine's state, got a batch of shape {pixels.shape[:-2]}")
    return "\n".join("".join(on if p else off for p in row) for row in pixels)
