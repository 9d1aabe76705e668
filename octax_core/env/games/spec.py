"""`GameSpec`: everything that turns a CHIP-8 ROM into an RL environment, as one frozen value.

A spec is pure data plus small pure functions of the machine state; it knows nothing of the env
API (`octax_core.env.environment`) that runs it. Each game module in this package exports its specs.
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Optional, Union

import jax
import jax.numpy as jnp

from octax_core.emulator.platforms import resolve_platform
from octax_core.emulator.quirks import Quirks
from octax_core.emulator.state import MEMORY_OFFSET, MachineState

StateFn = Callable[[MachineState], jax.Array]


@dataclasses.dataclass(frozen=True)
class GameSpec:
    """One game as an environment.

    Attributes:
        id: registry id, e.g. "Pong" (Gymnasium id `octax/Pong-v0`).
        title: human title, e.g. "Pong (1 player)".
        rom_file: file name of the ROM in the ROM store.
        rom_sha1: SHA-1 of the ROM bytes; a ROM with another hash is refused.
        action_keys: CHIP-8 key held by actions 1..k (action 0 is no-op).
        score_fn: state -> score (int32 or float32 scalar); the reward is its change per step.
        terminated_fn: state -> bool scalar, true once the game is over.
        lives_fn: state -> lives left (int32), where the game keeps a count; else None.
        startup: (key mask, frames) pairs run once after boot to get past menus; the resulting
            state is the template every reset starts from.
        platform: the machine the ROM is written for: "chip8" (default), "schip" or "xochip".
        quirks: the interpreter profile this ROM plays correctly under; None (the default) takes
            the platform's own profile.
        palette: the game's own colours for rendering, 2 (off, on) or, for XO-CHIP, 4 (off,
            plane 1, plane 2, both) RGB triples; None uses the renderer's default.
        freeze_timers: zero the delay and sound timers after every env step, as the octax
            package does for most games (its `disable_delay`); off means real 60 Hz timers.
        survival_reward: added to the reward of every step after which the game is still on (not
            the step that ends it), for a game that keeps no score: survival is then its return.
            0 (the default) adds nothing, and the step's traced program is unchanged.
        instructions_per_frame: the speed the game is written for (the archive's "tickrate");
            None (the default) takes `EnvConfig`'s, 11, about the COSMAC VIP's pace.
        max_episode_steps: default truncation (env steps of `frames_per_step` frames).
        category: the paper's category (see `CATEGORIES`).
        description: one paragraph: goal, keys, reward, termination.
        version: bumped when behaviour changes (the Gymnasium id's -vN).
    """

    id: str
    title: str
    rom_file: str
    rom_sha1: str
    action_keys: tuple[int, ...]
    score_fn: StateFn
    terminated_fn: StateFn
    category: str
    description: str
    lives_fn: Optional[StateFn] = None
    startup: tuple[tuple[int, int], ...] = ()
    platform: str = "chip8"
    quirks: Union[str, Quirks, None] = None
    palette: Optional[tuple[tuple[int, int, int], ...]] = None
    freeze_timers: bool = False
    instructions_per_frame: Optional[int] = None
    survival_reward: float = 0.0
    max_episode_steps: int = 5000
    version: int = 0

    def __post_init__(self):
        platform = resolve_platform(self.platform)  # an unknown name raises, listing the valid ones
        if self.quirks is None:
            object.__setattr__(self, "quirks", platform.default_quirks)
        if not self.action_keys or any(not 0 <= k <= 15 for k in self.action_keys):
            raise ValueError(f"{self.id}: action_keys must be CHIP-8 keys 0..15, got {self.action_keys}")
        if len(set(self.action_keys)) != len(self.action_keys):
            raise ValueError(f"{self.id}: action_keys repeat a key: {self.action_keys}")
        if self.category not in CATEGORIES:
            raise ValueError(f"{self.id}: unknown category {self.category!r}; valid: {', '.join(CATEGORIES)}")
        for mask, frames in self.startup:
            if not (0 <= mask <= 0xFFFF and frames >= 0):
                raise ValueError(f"{self.id}: startup steps are (key mask 0..0xFFFF, frames >= 0), got {(mask, frames)}")
        if self.instructions_per_frame is not None and self.instructions_per_frame <= 0:
            raise ValueError(f"{self.id}: instructions_per_frame must be positive, got {self.instructions_per_frame}")
        if self.max_episode_steps <= 0:
            raise ValueError(f"{self.id}: max_episode_steps must be positive, got {self.max_episode_steps}")


CATEGORIES = (
    "planning",  # Long-horizon planning & spatial reasoning
    "timing",  # Timing, prediction & reactive control
    "resources",  # Resource management & tactical decisions
    "navigation",  # Exploration & continuous navigation
    "reaction",  # Simple reaction & timing
)


def register_value(state: MachineState, index: int) -> jax.Array:
    """V[index] as int32, so that score arithmetic cannot wrap around at 256 as uint8 would."""
    return state.V[index].astype(jnp.int32)


def ram_value(state: MachineState, address: int, size: int = 1) -> jax.Array:
    """The `size` bytes of RAM at `address`, read big-endian as one int32 (a score kept in memory).

    The state stores RAM `MEMORY_OFFSET` bytes in (`octax_core.emulator.state`); this reads it
    where the program sees it.
    """
    value = jnp.int32(0)
    for offset in range(size):
        value = value * 256 + state.memory[MEMORY_OFFSET + address + offset].astype(jnp.int32)
    return value


def bcd_value(state: MachineState, address: int, digits: int = 3) -> jax.Array:
    """The decimal number whose digits (one per byte, most significant first, as FX33 writes
    them) are at `address`: a score the program keeps, or shows, as BCD."""
    value = jnp.int32(0)
    for offset in range(digits):
        value = value * 10 + state.memory[MEMORY_OFFSET + address + offset].astype(jnp.int32)
    return value


def in_routine(state: MachineState, start: int, end: int) -> jax.Array:
    """True while the program runs the code at start..end-1 or a subroutine it called from there:
    pc is in the range, or a return address on the stack is (a game-over routine that calls its
    drawing helpers is still the game over while they run)."""
    def inside(address):
        return (address >= start) & (address < end)

    depth = jnp.arange(state.stack.shape[0])
    called_from = inside(state.stack - 2) & (depth < state.sp.astype(depth.dtype))
    return inside(state.pc) | called_from.any()


def key_mask(*keys: int) -> int:
    """The 16-bit mask holding `keys`, for `GameSpec.startup`."""
    mask = 0
    for key in keys:
        mask |= 1 << key
    return mask
