"""`Machine`: the frozen configuration of an interpreter and its pure entry points.

The config (platform, quirks, instructions per frame) shapes the traced program, so it is a hashable
value closed over by `jit`, never a field of the state. Methods are pure functions of their
arguments: wrap them with `jax.jit` / `jax.vmap` as needed, e.g.
`jax.jit(machine.run_frames, static_argnums=2, compiler_options=machine.compiler_options)`
(the options are the platform's measured XLA settings: same results, faster kernels).
"""

from __future__ import annotations

import dataclasses
import operator
from typing import Union

import jax
import jax.numpy as jnp

from octax_core.emulator import cpu, frame, idle
from octax_core.emulator.keypad import keys_to_mask
from octax_core.emulator.platforms import Platform, check_program_fits, resolve_platform
from octax_core.emulator.quirks import Quirks, lane_quirks, resolve_quirks
from octax_core.emulator.rom import Rom, RomLike
from octax_core.emulator.state import MachineState, boot_state
from octax_core.validate import check_bool, check_int


@dataclasses.dataclass(frozen=True)
class Machine:
    """An interpreter configuration: which machine, how it behaves, how fast it runs.

    Args:
        platform: "chip8" (64x32, 4 KiB), "schip" (SUPER-CHIP: 128x64 and 64x32 modes, scrolling,
            16x16 sprites, big digits, flags, exit) or "xochip" (XO-CHIP: SUPER-CHIP plus 64 KiB,
            two bit planes, long I, register ranges, audio registers); or a `Platform`.
        quirks: a profile name ("chip8", "schip", "xochip"; `QUIRK_PROFILES`) or a `Quirks`;
            None (the default) takes the platform's own profile, the one of the same name.
        instructions_per_frame: instructions run per 60 Hz frame (11 is about the COSMAC VIP's
            speed on typical game code).
        skip_idle: fast-forward the rest of a frame once the program provably spins (an exact
            cycle of its registers with no memory or screen write: timer waits, key polls, FX0A),
            and give each machine of a batch its own frame clock (`octax_core.emulator.idle`).
            Bit-identical to running every instruction; False runs every one, in lockstep. It
            takes effect from `idle.SKIP_FROM` (25) instructions per frame: a shorter frame has
            too little to skip for the clock's bookkeeping to pay, and runs plain.
        profiles: for a batch whose machines run different games (`octax_core.make_mix`): one
            (quirks, instructions_per_frame) pair per game, each machine running the one its
            `profile` index picks (`run_frames(..., profile=i)`); quirks the profiles share stay
            constants of the traced program, the others are looked up per machine. `quirks` and
            `instructions_per_frame` are then the first profile's and the largest; every
            profile's quirks must be given as a `Quirks` or a profile name. Empty (the default):
            one profile, the one above.

    Example:
        >>> import jax, octax_core
        >>> machine = octax_core.Machine("chip8")
        >>> state = machine.boot(bytes([0x12, 0x00]), jax.random.key(0))  # jump-to-self loop
        >>> state = machine.run_frames(state, 0, 2)
        >>> int(state.pc)
        512
    """

    platform: Union[Platform, str] = "chip8"
    quirks: Union[Quirks, str, None] = None
    instructions_per_frame: int = 11
    skip_idle: bool = True
    profiles: tuple[tuple[Union[Quirks, str], int], ...] = ()

    def __post_init__(self):
        platform = resolve_platform(self.platform)
        object.__setattr__(self, "platform", platform)
        if self.profiles:
            profiles = tuple((resolve_quirks(quirks), check_int("instructions_per_frame", ipf))
                             for quirks, ipf in self.profiles)
            object.__setattr__(self, "profiles", profiles)
            object.__setattr__(self, "quirks", profiles[0][0])
            object.__setattr__(self, "instructions_per_frame", max(ipf for _, ipf in profiles))
        object.__setattr__(self, "quirks", resolve_quirks(platform.default_quirks if self.quirks is None else self.quirks))
        object.__setattr__(self, "instructions_per_frame",
                           check_int("instructions_per_frame", self.instructions_per_frame))
        object.__setattr__(self, "skip_idle", check_bool("skip_idle", self.skip_idle))

    def boot(self, rom: RomLike, key: jax.Array) -> MachineState:
        """A powered-on machine with `rom` loaded at 0x200; the key seeds CXNN.

        Jittable and vmappable over `key` (the ROM is baked in as a constant).

        Raises:
            ValueError: the ROM is empty, or larger than the platform holds (3584 bytes on
                chip8 and schip, 65024 on xochip).
        """
        rom = Rom.load(rom)
        check_program_fits(len(rom.data), rom.name, self.platform)
        return boot_state(rom, key, self.platform)

    def execute(self, state: MachineState, keys, *, profile=None) -> MachineState:
        """Runs exactly one instruction (no timer tick, no display wait; after 00FD, nothing);
        `profile` as for `run_frames`."""
        stalled = None if state.extension is None else state.extension.exited
        quirks = self.quirks if not self.profiles else lane_quirks([q for q, _ in self.profiles],
                                                                    self._profile(profile))
        new_state, _ = cpu.execute(self.platform, quirks, state, keys_to_mask(keys), stalled)
        return new_state

    def run_frames(self, state: MachineState, keys, frames, *, halted=None, record_screens: bool = False,
                   profile=None):
        """Runs `frames` 60 Hz frames with `keys` held throughout: the one frame loop.

        Args:
            state: one machine (vmap for a batch).
            keys: bool[16] or an integer mask, bit k = key k.
            frames: how many frames. A Python int fixes the loop length at trace time (mark it
                static under jit); an integer scalar array may be traced, so one compile serves
                every count (not with `record_screens`, whose output has `frames` rows).
            halted: optional bool scalar; where true nothing runs, the timers do not tick and
                the state comes back unchanged (the env halts episodes that have ended).
            record_screens: also return the packed picture after each frame (`state.display`).
            profile: with `profiles`, the machine's index into them (an int or int32 scalar,
                traced or not); required then, and refused without.

        Returns:
            The state after the frames; with `record_screens`, `(state, screens)` where screens
            is (frames, 32, 2) uint32 on CHIP-8, (frames, planes, 64, 4) on SUPER-CHIP and
            XO-CHIP, lores pictures doubled (`octax_core.emulator.state.unpack_screen` unpacks either).

        Raises:
            TypeError: `frames` is neither an int nor an integer scalar array, or is an array
                while `record_screens` is set.
            ValueError: a negative frame count given as an int.
        """
        mask = keys_to_mask(keys)
        halted = jnp.zeros_like(state.pc, dtype=jnp.bool_) if halted is None else jnp.asarray(halted, jnp.bool_)
        profile = self._profile(profile)
        if isinstance(frames, jax.Array) and not record_screens:
            _check_traced_frames(frames)
            one = self._runner(1, False)
            return jax.lax.fori_loop(0, frames, lambda _, state: one(state, mask, halted, profile)[0], state)
        frames = _check_static_frames(frames, record_screens)
        state, screens = self._runner(frames, record_screens)(state, mask, halted, profile)
        return (state, screens) if record_screens else state

    def _profile(self, profile) -> jax.Array:
        """The machine's profile index as int32 (0, unused, for a machine of one profile)."""
        if not self.profiles:
            if profile is not None:
                raise ValueError("profile= is for a Machine with profiles (a mix of games); this one has one profile")
            return jnp.int32(0)
        if profile is None:
            raise ValueError(f"this Machine runs {len(self.profiles)} profiles: give run_frames/execute "
                             f"profile=0..{len(self.profiles) - 1}")
        if not isinstance(profile, jax.core.Tracer):
            value = int(profile)
            if not 0 <= value < len(self.profiles):
                raise ValueError(f"profile {value} is out of range; valid: 0..{len(self.profiles) - 1}")
        return jnp.asarray(profile, jnp.int32)

    @property
    def compiler_options(self) -> dict[str, object]:
        """The `compiler_options` for `jax.jit` of this machine's programs: its platform's
        (`Platform.compiler_options`). They change speed only; a plain `jax.jit` gives the same results."""
        return self.platform.compiler_options

    @property
    def skipping(self) -> bool:
        """Whether idle skipping takes effect: asked for, and at >= `idle.SKIP_FROM` instructions a frame."""
        return self.skip_idle and self.instructions_per_frame >= idle.SKIP_FROM

    def _runner(self, frames: int, record_screens: bool):
        return frame.frame_runner(self.platform, self.quirks, self.instructions_per_frame, frames, record_screens,
                                  self.skipping, profiles=self.profiles)


def _check_traced_frames(frames: jax.Array) -> None:
    if frames.shape != () or not jnp.issubdtype(frames.dtype, jnp.integer):
        raise TypeError(f"frames must be an int or an integer scalar array, got {frames.dtype} {frames.shape}")


def _check_static_frames(frames, record_screens: bool) -> int:
    try:
        frames = operator.index(frames)
    except TypeError:
        raise TypeError(
            f"frames must be a Python int (mark it static under jit){'' if record_screens else ' or an integer scalar array'}, "
            f"got {type(frames).__name__}"
        ) from None
    if frames < 0:
        raise ValueError(f"frames must be >= 0, got {frames}")
    return frames
