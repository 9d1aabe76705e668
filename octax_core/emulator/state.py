"""The machine state pytree, boot image, and host-side views of a state.

Everything a running program can change is here, as arrays with explicit dtypes; nothing that
configures the machine is (that lives in `Machine`). The screen is packed, 32 rows of two uint32
words on CHIP-8, because a sprite draw is then a shift, an AND and an XOR over a few words.
SUPER-CHIP and XO-CHIP machines add one optional part, `Extension` (None on a CHIP-8 machine,
so that its pytree, and every program traced over it, stays what it was): among its fields the
128x64 hires grid. Their 64x32 lores picture stays in `screen`, one 64x32 surface per plane, so
that lores work is CHIP-8's (`ops.display`); `display` gives the picture as it is seen.
"""

from __future__ import annotations

import dataclasses
from typing import Optional

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.ops.display import upscale
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
class Extension:
    """What SUPER-CHIP and XO-CHIP add to a machine's state (one machine; batch with leading axes)."""

    hires: jax.Array  # () bool, 128x64 mode (00FF) rather than 64x32 (00FE)
    grid: jax.Array  # (planes, 64, 4) uint32, the hires picture (all dark in lores, as `screen` is in hires)
    flags: jax.Array  # (16,) uint8, FX75 / FX85's persistent flag registers
    exited: jax.Array  # () bool, 00FD ran: the program has ended and the machine stands still
    plane: jax.Array  # () uint8, FN01's plane mask 0..3 (bit 0 plane 1, bit 1 plane 2); SUPER-CHIP: 1
    audio_pattern: jax.Array  # (16,) uint8, XO-CHIP's F002 128-bit audio pattern
    pitch: jax.Array  # () uint8, XO-CHIP's FX3A playback pitch (64 = 4000 Hz)

    def replace(self, **changes) -> "Extension":
        return dataclasses.replace(self, **changes)


# The fields `snapshot` shows per extended platform (SUPER-CHIP has no planes or audio to show).
EXTENSION_FIELDS = {"schip": ("hires", "flags", "exited"),  # the grid is in `screen`, as seen
                    "xochip": ("hires", "flags", "exited", "plane", "audio_pattern", "pitch")}


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class MachineState:
    """One machine's mutable state, on any platform (add leading axes to batch it)."""

    memory: jax.Array  # (4192,) uint8: scratch, RAM, mirror (see MEMORY_OFFSET)
    V: jax.Array  # (16,) uint8, registers V0..VF
    I: jax.Array  # () uint16, always < 0x1000
    pc: jax.Array  # () uint16, always < 0x1000
    sp: jax.Array  # () uint8, 0..15
    stack: jax.Array  # (16,) uint16
    delay_timer: jax.Array  # () uint8
    sound_timer: jax.Array  # () uint8
    screen: jax.Array  # (32, 2) uint32, the 64x32 picture (row y, word x // 32, bit 31 - x % 32); (planes, 32, 2) after CHIP-8
    rng: jax.Array  # () uint32, xorshift32 state, never 0
    key_wait: jax.Array  # () uint8, FX0A: NO_KEY or the key seen pressed
    extension: Optional[Extension] = None  # SUPER-CHIP and XO-CHIP only

    @property
    def exited(self) -> jax.Array:
        """Whether 00FD has ended the program (always false on CHIP-8, which has no 00FD)."""
        if self.extension is None:
            return jnp.zeros_like(self.key_wait, dtype=jnp.bool_)
        return self.extension.exited

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
    """The platform a state belongs to, for host-side views that get a state alone: each
    platform's stored memory has its own length (`stored_memory_size`)."""
    return platform_of_memory(state.memory)


def platform_of_memory(memory) -> Platform:
    """The platform whose stored memory is `memory` (leading axes allowed), from its length."""
    length = memory.shape[-1]
    for platform in PLATFORMS.values():
        if stored_memory_size(platform) == length:
            return platform
    known = ", ".join(f"{stored_memory_size(p)} ({p.name})" for p in PLATFORMS.values())
    raise ValueError(f"a stored memory of {length} bytes belongs to no platform; the lengths are {known}")


def ram_view(memory):
    """The RAM inside the stored layout: 4 KiB, or 64 KiB on XO-CHIP."""
    return memory[..., MEMORY_OFFSET : MEMORY_OFFSET + platform_of_memory(memory).memory_size]


def seed_rng(key: jax.Array) -> jax.Array:
    """A nonzero xorshift32 state drawn from a JAX key (zero is xorshift's fixed point)."""
    bits = jax.random.bits(key, dtype=jnp.uint32)
    return jnp.where(bits == 0, jnp.uint32(0x9E3779B9), bits)


def boot_state(rom: Rom, key: jax.Array, platform: Platform = PLATFORMS["chip8"]) -> MachineState:
    """A freshly powered-on `platform` machine with `rom` loaded; jittable and vmappable over `key`."""
    extension = None
    screen = jnp.zeros((SCREEN_HEIGHT, 2), jnp.uint32)
    if platform.extended:
        screen = jnp.zeros((platform.planes, SCREEN_HEIGHT, 2), jnp.uint32)
        grid = jnp.zeros((platform.planes, GRID_HEIGHT, GRID_WIDTH // 32), jnp.uint32)
        extension = Extension(hires=jnp.bool_(False), grid=grid, flags=jnp.zeros(16, jnp.uint8),
                              exited=jnp.bool_(False), plane=jnp.uint8(1), audio_pattern=jnp.zeros(16, jnp.uint8),
                              pitch=jnp.uint8(64))
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
        extension=extension,
    )


def display(screen, grid=None, hires=None):
    """The packed picture a machine shows: CHIP-8's (..., 32, 2) screen as it is; on SUPER-CHIP
    and XO-CHIP the (..., planes, 64, 4) grid in hires (`hires` true), the (..., planes, 32, 2)
    lores screen doubled to that size in lores. numpy in, numpy out; jittable."""
    if grid is None:
        return screen
    xp = np if isinstance(grid, np.ndarray) else jnp
    hires = xp.asarray(hires).reshape(xp.shape(hires) + (1, 1, 1))
    return xp.where(hires, grid, upscale(screen))


def shown(state: MachineState):
    """`display` of a state: the packed picture it shows."""
    if state.extension is None:
        return state.screen
    return display(state.screen, state.extension.grid, state.extension.hires)


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
    XLA:CPU compiles it to a scalar loop instead of vector code (its cost: docs/machine-log.md).
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
            if field.name != "extension"}
    if state.extension is not None:
        view.update({name: np.asarray(getattr(state.extension, name))
                     for name in EXTENSION_FIELDS[platform_of(state).name]})
    view["memory"] = ram_view(view["memory"])
    view["screen"] = screen_pixels(state)
    return view


def screen_pixels(state: MachineState) -> np.ndarray:
    """The picture as numpy bool pixels in `snapshot`'s shape for the state's platform."""
    platform = platform_of(state)
    picture = np.asarray(state.screen)
    if state.extension is not None:
        picture = display(picture, np.asarray(state.extension.grid), np.asarray(state.extension.hires))
    pixels = np.asarray(unpack_screen(picture))
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
