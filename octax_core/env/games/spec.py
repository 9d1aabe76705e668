"""`GameSpec`: everything that turns a CHIP-8 ROM into an RL environment, as one frozen value.

A spec is pure data plus small pure functions of the machine state; it knows nothing of the env
API (`octax_core.env.environment`) that runs it. Each game module in this package exports its specs.
"""

from __future__ import annotations

import dataclasses
import re
from typing import Callable, Optional, Union

import jax
import jax.numpy as jnp

from octax_core.emulator.platforms import resolve_platform
from octax_core.emulator.quirks import Quirks
from octax_core.emulator.state import MEMORY_OFFSET, MachineState

StateFn = Callable[[MachineState], jax.Array]


MIRROR_AXES = ("left-right", "top-bottom")  # `Seats.mirror`: the screen flipped across its columns, or its rows


@dataclasses.dataclass(frozen=True)
class Seats:
    """How two players share one machine: each seat's keys, each seat's score, whose turn it is.

    Both seats' keys reach the one keypad in the same step (a key held by either is held), as on
    the real machine, where two people press one hex keypad (or one PC keyboard) together.

    Attributes:
        action_keys: per seat, the CHIP-8 keys its actions 1..k hold (action 0 is no-op). Every
            seat has the same number of actions; seats may share keys (a hot-seat game whose two
            players type on the same keys in turn).
        score_fn: state -> (seats,) scores, one per seat (int32 or float32); a seat's reward is
            the change of its score over the step.
        turn_fn: state -> int32 seat to move, for a turn-based game; None (the default) for a
            simultaneous one. The seat whose turn it is not may only play no-op (its legal mask
            holds action 0 alone); the functional env turns any other action of it into no-op.
        legal_fn: state -> (num_actions,) bool, the actions open to the seat to move (action 0,
            no-op, is always open); None (the default) opens every action.
        zero_sum: the seats' rewards sum to 0 on every step (a win is the other's loss).
        startup: the two-player mode's start-up, replacing `GameSpec.startup` in the multi-agent
            env (a menu that picks one or two players); None keeps the spec's.
        names: the seats' names in the game (for docs and renderers): "left ship", "X".
        scripted_policy: (state, seat) -> int32 action: a hand-written player for either seat
            that reads the machine (registers, RAM) as a bot would, pure JAX so that it runs
            batched inside a jitted rollout (`seat` is a Python int); the opponent self-play is
            evaluated against. None where the game has none.
        mirror: the axis across which the two sides are each other's mirror image, "left-right"
            or "top-bottom" (`MIRROR_AXES`), for a game whose rules treat the seats alike; None
            (the default) where they differ. Declared only where measured: `make_multi(...,
            mirror=True)` then shows seat 1 the flipped screen, so one network sees both seats
            from seat 0's side (docs/multiplayer.md, "Mirrored seats").
        mirror_actions: with `mirror`, the action seat 1 plays in the mirrored view for each of
            its actions: a permutation of 0..num_actions-1 that keeps no-op (0) and is its own
            inverse (left and right keys swapped). Required with `mirror`, refused without it.
    """

    action_keys: tuple[tuple[int, ...], ...]
    score_fn: StateFn
    turn_fn: Optional[StateFn] = None
    legal_fn: Optional[StateFn] = None
    zero_sum: bool = False
    startup: Optional[tuple[tuple[int, int], ...]] = None
    names: tuple[str, ...] = ("player 1", "player 2")
    scripted_policy: Optional[Callable[[MachineState, int], jax.Array]] = None
    mirror: Optional[str] = None
    mirror_actions: Optional[tuple[int, ...]] = None

    def __post_init__(self):
        if len(self.action_keys) != 2:
            raise ValueError(f"Seats: two seats are supported, got {len(self.action_keys)}")
        counts = {len(keys) for keys in self.action_keys}
        if len(counts) != 1 or 0 in counts:
            raise ValueError(f"Seats: every seat needs the same number (>= 1) of action keys, got {self.action_keys}")
        for keys in self.action_keys:
            if any(not 0 <= k <= 15 for k in keys) or len(set(keys)) != len(keys):
                raise ValueError(f"Seats: a seat's keys are distinct CHIP-8 keys 0..15, got {keys}")
        if len(self.names) != len(self.action_keys):
            raise ValueError(f"Seats: one name per seat, got {self.names}")
        if self.mirror is not None and self.mirror not in MIRROR_AXES:
            raise ValueError(f"Seats: unknown mirror axis {self.mirror!r}; valid: {', '.join(MIRROR_AXES)}")
        if (self.mirror is None) != (self.mirror_actions is None):
            raise ValueError("Seats: mirror and mirror_actions go together (both or neither), got "
                             f"mirror={self.mirror!r}, mirror_actions={self.mirror_actions}")
        if self.mirror_actions is not None:
            count = len(self.action_keys[0]) + 1
            permutation = tuple(self.mirror_actions)
            if (sorted(permutation) != list(range(count)) or permutation[0] != 0
                    or any(permutation[permutation[a]] != a for a in range(count))):
                raise ValueError(f"Seats: mirror_actions must be a permutation of 0..{count - 1} that keeps 0 and "
                                 f"is its own inverse, got {self.mirror_actions}")

    @property
    def players(self) -> int:
        return len(self.action_keys)

    @property
    def turn_based(self) -> bool:
        return self.turn_fn is not None


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
        version: bumped when behaviour changes (the Gymnasium id's -vN). A changed game that
            keeps its old version registered beside it (Duel-v0 and Duel-v1) takes the id
            "<Name>-v<version>" ("Duel-v1"): the id stays unique in the registry, and its
            Gymnasium id is octax/<Name>-v<version> (`base_id`).
        seats: a two-player game's `Seats` (`octax_core.make_multi` builds its multi-agent env);
            None (the default) for a one-player game.
        solo: the game is also a one-player env (`make`; player 2, where there is one, holds no
            key). A turn-based game that waits for its second player is not: False leaves it out
            of `list_games()` and refuses `make`; it is played by `make_multi`, or alone against
            a fixed opponent in the Gymnasium layer.
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
    seats: Optional[Seats] = None
    solo: bool = True

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
        if not self.solo and self.seats is None:
            raise ValueError(f"{self.id}: a game that is not solo must have seats (it is played by two)")
        suffix = _VERSION_SUFFIX.search(self.id)
        if suffix and int(suffix.group(1)) != self.version:
            raise ValueError(f"{self.id}: an id ending in -v{suffix.group(1)} names that version; its version is "
                             f"{self.version}")

    @property
    def base_id(self) -> str:
        """The game's name without a version suffix: "Duel" for "Duel-v1" (the Gymnasium id's name)."""
        return _VERSION_SUFFIX.sub("", self.id)

    @property
    def players(self) -> int:
        """The most players the game takes: 2 where it has `seats`, else 1."""
        return 1 if self.seats is None else self.seats.players


_VERSION_SUFFIX = re.compile(r"-v(\d+)$")  # "Duel-v1": the id of a game's version 1 registered beside its v0

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
