"""The machine state pytree, boot image, and host-side views of a state.

Everything a running program can change is here, as arrays with explicit dtypes; nothing that
configures the machine is (that lives in `Machine`). The screen is packed, 32 rows of two uint32
words, because a sprite draw is then a shift, an AND and an XOR over a few words. SUPER-CHIP and
XO-CHIP machines add their own fields (None on a CHIP-8 machine, so that its pytree, and every
program traced over it, stays what it was) and pack a (planes, 64, 4) uint32 screen.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.platforms import PLATFORMS, Platform
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
# SUPER-CHIP's 16 big digits (FX30), 8x10 pixels, one byte a row: the shapes every SUPER-CHIP
# interpreter since the HP48's ships (docs/machine.md draws them). XO-CHIP has them too.
BIG_FONT_ADDRESS = 0xA0
BIG_FONT = bytes([
    0xFF, 0xFF, 0xC3, 0xC3, 0xC3, 0xC3, 0xC3, 0xC3, 0xFF, 0xFF,  # 0
    0x18, 0x78, 0x78, 0x18, 0x18, 0x18, 0x18, 0x18, 0xFF, 0xFF,  # 1
    0xFF, 0xFF, 0x03, 0x03, 0xFF, 0xFF, 0xC0, 0xC0, 0xFF, 0xFF,  # 2
    0xFF, 0xFF, 0x03, 0x03, 0xFF, 0xFF, 0x03, 0x03, 0xFF, 0xFF,  # 3
    0xC3, 0xC3, 0xC3, 0xC3, 0xFF, 0xFF, 0x03, 0x03, 0x03, 0x03,  # 4
    0xFF, 0xFF, 0xC0, 0xC0, 0xFF, 0xFF, 0x03, 0x03, 0xFF, 0xFF,  # 5
    0xFF, 0xFF, 0xC0, 0xC0, 0xFF, 0xFF, 0xC3, 0xC3, 0xFF, 0xFF,  # 6
    0xFF, 0xFF, 0x03, 0x03, 0x06, 0x0C, 0x18, 0x18, 0x18, 0x18,  # 7
    0xFF, 0xFF, 0xC3, 0xC3, 0xFF, 0xFF, 0xC3, 0xC3, 0xFF, 0xFF,  # 8
    0xFF, 0xFF, 0xC3, 0xC3, 0xFF, 0xFF, 0x03, 0x03, 0xFF, 0xFF,  # 9
    0x7E, 0xFF, 0xC3, 0xC3, 0xC3, 0xFF, 0xFF, 0xC3, 0xC3, 0xC3,  # A
    0xFC, 0xFC, 0xC3, 0xC3, 0xFC, 0xFC, 0xC3, 0xC3, 0xFC, 0xFC,  # B
    0x3C, 0xFF, 0xC3, 0xC0, 0xC0, 0xC0, 0xC0, 0xC3, 0xFF, 0x3C,  # C
    0xFC, 0xFE, 0xC3, 0xC3, 0xC3, 0xC3, 0xC3, 0xC3, 0xFE, 0xFC,  # D
    0xFF, 0xFF, 0xC0, 0xC0, 0xFF, 0xFF, 0xC0, 0xC0, 0xFF, 0xFF,  # E
    0xFF, 0xFF, 0xC0, 0xC0, 0xFF, 0xFF, 0xC0, 0xC0, 0xC0, 0xC0,  # F
])
SCREEN_HEIGHT, SCREEN_WIDTH = 32, 64
GRID_HEIGHT, GRID_WIDTH = 64, 128  # SUPER-CHIP and XO-CHIP: the hires grid, lores pixels are 2x2
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
# SUPER-CHIP and XO-CHIP read a sprite as one 64-byte slice at I (16x16, two planes), so their
# tail keeps 64 bytes in step with RAM 0x000..0x03F, and is 80 long: a 16-byte write at
# I < 64 repeats at I + memory size and must fit.
EXTENDED_MIRROR_SIZE = 80
EXTENDED_MIRRORED = 64


def tail_size(platform: Platform) -> int:
    """Bytes stored after RAM on `platform`."""
    return EXTENDED_MIRROR_SIZE if platform.extended else MIRROR_SIZE


def stored_memory_size(platform: Platform) -> int:
    """Length of `MachineState.memory` on `platform`: 4192 (chip8), 4208 (schip), 65648 (xochip)."""
    return MEMORY_OFFSET + platform.memory_size + tail_size(platform)


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
    # SUPER-CHIP and XO-CHIP only (None on CHIP-8):
    hires: jax.Array = None  # () bool, 128x64 mode (00FF) rather than 64x32 (00FE)
    flags: jax.Array = None  # (16,) uint8, FX75 / FX85's persistent flag registers
    exited: jax.Array = None  # () bool, 00FD ran: the program has ended and the machine stands still
    # XO-CHIP only:
    plane: jax.Array = None  # () uint8, FN01's plane mask 0..3 (bit 0 plane 1, bit 1 plane 2)
    audio_pattern: jax.Array = None  # (16,) uint8, F002's 128-bit audio pattern
    pitch: jax.Array = None  # () uint8, FX3A's playback pitch (64 = 4000 Hz)

    def replace(self, **changes) -> "MachineState":
        return dataclasses.replace(self, **changes)


def boot_memory(rom: Rom, platform: Platform = PLATFORMS["chip8"]) -> np.ndarray:
    """The stored memory at power-on: font at 0x50 (big digits at 0xA0 after CHIP-8), program at
    0x200, then the mirror."""
    ram = np.zeros(platform.memory_size, np.uint8)
    ram[FONT_ADDRESS : FONT_ADDRESS + len(FONT)] = np.frombuffer(FONT, np.uint8)
    if platform.extended:
        ram[BIG_FONT_ADDRESS : BIG_FONT_ADDRESS + len(BIG_FONT)] = np.frombuffer(BIG_FONT, np.uint8)
    ram[PROGRAM_ADDRESS : PROGRAM_ADDRESS + len(rom.data)] = np.frombuffer(rom.data, np.uint8)
    return stored_memory(ram, platform)


def stored_memory(ram, platform: Platform = PLATFORMS["chip8"]):
    """`platform`'s RAM (numpy or JAX, leading axes allowed) -> the stored layout."""
    xp = np if isinstance(ram, np.ndarray) else jnp
    head = xp.zeros((*ram.shape[:-1], MEMORY_OFFSET), ram.dtype)
    return xp.concatenate([head, ram, ram[..., :tail_size(platform)]], axis=-1)


def platform_of(state: "MachineState") -> Platform:
    """The platform a state belongs to, read from which optional fields it has (static)."""
    if state.hires is None:
        return PLATFORMS["chip8"]
    return PLATFORMS["schip" if state.plane is None else "xochip"]


def ram_size(memory) -> int:
    """The RAM size inside a stored memory (leading axes allowed): each platform's stored length
    is its own (`stored_memory_size`)."""
    length = memory.shape[-1]
    for platform in PLATFORMS.values():
        if stored_memory_size(platform) == length:
            return platform.memory_size
    known = ", ".join(f"{stored_memory_size(p)} ({p.name})" for p in PLATFORMS.values())
    raise ValueError(f"a stored memory of {length} bytes belongs to no platform; the lengths are {known}")


def ram_view(memory):
    """The RAM inside the stored layout: 4 KiB, or 64 KiB on XO-CHIP."""
    return memory[..., MEMORY_OFFSET : MEMORY_OFFSET + ram_size(memory)]


def seed_rng(key: jax.Array) -> jax.Array:
    """A nonzero xorshift32 state drawn from a JAX key (zero is xorshift's fixed point)."""
    bits = jax.random.bits(key, dtype=jnp.uint32)
    return jnp.where(bits == 0, jnp.uint32(0x9E3779B9), bits)


def boot_state(rom: Rom, key: jax.Array, platform: Platform = PLATFORMS["chip8"]) -> MachineState:
    """A freshly powered-on `platform` machine with `rom` loaded; jittable and vmappable over `key`."""
    extended, xochip = {}, {}
    if platform.extended:
        screen = jnp.zeros((platform.planes, GRID_HEIGHT, GRID_WIDTH // 32), jnp.uint32)
        extended = dict(hires=jnp.bool_(False), flags=jnp.zeros(16, jnp.uint8), exited=jnp.bool_(False))
        if platform.planes > 1:
            xochip = dict(plane=jnp.uint8(1), audio_pattern=jnp.zeros(16, jnp.uint8), pitch=jnp.uint8(64))
    else:
        screen = jnp.zeros((SCREEN_HEIGHT, 2), jnp.uint32)
    return MachineState(
        memory=jnp.asarray(boot_memory(rom, platform)),
        V=jnp.zeros(16, jnp.uint8),
        I=jnp.uint16(0),
        pc=jnp.uint16(PROGRAM_ADDRESS),
        sp=jnp.uint8(0),
        stack=jnp.zeros(16, jnp.uint16),
        delay_timer=jnp.uint8(0),
        sound_timer=jnp.uint8(0),
        screen=screen,
        rng=seed_rng(key),
        key_wait=jnp.uint8(NO_KEY),
        **extended,
        **xochip,
    )


def unpack_screen(screen, on=True, dtype=jnp.bool_):
    """(..., rows, W) packed words -> (..., rows, 32 W) pixels, row 0 at the top; numpy in, numpy out.

    CHIP-8's (..., 32, 2) screen unpacks to (..., 32, 64), SUPER-CHIP and XO-CHIP's
    (..., planes, 64, 4) to (..., planes, 64, 128).

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
    return bits.reshape(*screen.shape[:-1], 32 * screen.shape[-1])


def screen_values(screen, platform: Platform, on: int = 1, dtype=jnp.uint8):
    """Packed screens (leading axes allowed) -> one value per pixel: what an env observes.

    CHIP-8 gives (..., 32, 64) and SUPER-CHIP (..., 64, 128): lit pixels `on` (1 or 255), dark 0.
    XO-CHIP gives (..., 64, 128) with each pixel's plane combination kept apart, so that its four
    colours stay four: code = plane 1 + 2 x plane 2 (0 dark, 1 plane 1 only, 2 plane 2 only,
    3 both), times 85 when `on` is 255 (0, 85, 170, 255). numpy in, numpy out; jittable.
    """
    if not platform.extended:
        return unpack_screen(screen, on=on, dtype=dtype)
    if platform.planes == 1:
        return unpack_screen(screen[..., 0, :, :], on=on, dtype=dtype)
    bits = unpack_screen(screen, on=1, dtype=dtype)
    codes = bits[..., 0, :, :] + bits[..., 1, :, :] * 2
    return codes * (on // 3) if on != 1 else codes


def screen_values_shape(platform: Platform) -> tuple[int, int]:
    """The (height, width) `screen_values` gives: (32, 64) on CHIP-8, (64, 128) after it."""
    return (GRID_HEIGHT, GRID_WIDTH) if platform.extended else (SCREEN_HEIGHT, SCREEN_WIDTH)


def screen_values_max(platform: Platform, on: int = 1) -> int:
    """The largest value `screen_values` gives: `on`, or 3 on XO-CHIP with on = 1 (its plane codes)."""
    return 3 if platform.planes > 1 and on == 1 else on


def snapshot(state: MachineState) -> dict[str, np.ndarray]:
    """The state as a dict of numpy arrays, with the screen unpacked.

    `screen` is (32, 64) bool on CHIP-8, (64, 128) on SUPER-CHIP and (2, 64, 128) on XO-CHIP
    (plane 1 first; in lores each pixel is a 2x2 block of that grid); `memory` is the RAM alone
    (4096 or 65536 bytes). Fields a platform does not have (None) are left out. Leading batch
    axes are kept. Meant for tests, debugging and tools; it syncs with the device.
    """
    view = {field.name: np.asarray(getattr(state, field.name)) for field in dataclasses.fields(state)
            if getattr(state, field.name) is not None}
    view["memory"] = ram_view(view["memory"])
    view["screen"] = screen_pixels(state)
    return view


def screen_pixels(state: MachineState) -> np.ndarray:
    """The screen as numpy bool pixels in `snapshot`'s shape for the state's platform."""
    platform = platform_of(state)
    pixels = np.asarray(unpack_screen(np.asarray(state.screen)))
    if platform.extended and platform.planes == 1:
        pixels = pixels[..., 0, :, :]
    return pixels


def poke(state: MachineState, address: int, data) -> MachineState:
    """Writes `data` (bytes or uint8 array) to memory at `address`, wrapping at the memory size.

    Used to set up a program before it runs, e.g. the quirks test ROM's mode byte at 0x1FF.
    """
    platform = platform_of(state)
    values = jnp.asarray(np.frombuffer(bytes(data), np.uint8) if isinstance(data, (bytes, bytearray)) else data, jnp.uint8)
    addresses = (address + np.arange(values.shape[-1])) % platform.memory_size
    ram = ram_view(state.memory).at[..., addresses].set(values)
    return state.replace(memory=stored_memory(ram, platform))


PLANE_CHARACTERS = ".123"  # XO-CHIP text: dark, plane 1 only, plane 2 only, both


def render_text(state: MachineState, on: str = "#", off: str = ".") -> str:
    """The screen of one machine as text: 32 lines of 64 characters on CHIP-8, 64 of 128 on
    SUPER-CHIP and XO-CHIP. XO-CHIP shows each pixel's planes: `off`, "1", "2" or "3" (both)."""
    pixels = screen_pixels(state)
    platform = platform_of(state)
    planes = platform.planes if platform.planes > 1 else 0
    if pixels.ndim != 2 + (planes > 0):
        raise ValueError(f"render_text takes one machine's state, got a batch of shape {pixels.shape[:-2 - (planes > 0)]}")
    if planes:
        value = pixels[0].astype(np.uint8) + 2 * pixels[1].astype(np.uint8)
        chars = off + PLANE_CHARACTERS[1:]
        return "\n".join("".join(chars[v] for v in row) for row in value)
    return "\n".join("".join(on if p else off for p in row) for row in pixels)
