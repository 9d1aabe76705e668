"""`Machine`: the frozen configuration of a CHIP-8 interpreter and its pure entry points.

The config (quirks, instructions per frame) shapes the traced program, so it is a hashable
value closed over by `jit`, never a field of the state. Methods are pure functions of their
arguments: wrap them with `jax.jit` / `jax.vmap` as needed, e.g.
`jax.jit(machine.run_frames, static_argnums=2)`.
"""

from __future__ import annotations

import dataclasses
import operator
from typing import Union

import jax

from octax_core.emulator import cpu
from octax_core.emulator.keypad import keys_to_mask
from octax_core.emulator.quirks import Quirks, resolve_quirks
from octax_core.emulator.rom import Rom, RomLike
from octax_core.emulator.state import MachineState, boot_state


@dataclasses.dataclass(frozen=True)
class Machine:
    """A CHIP-8 interpreter configuration.

    Args:
        quirks: a profile name ("chip8", "schip") or a `Quirks`.
        instructions_per_frame: instructions run per 60 Hz frame (11 is about the COSMAC VIP's
            speed on typical game code).

    Example:
        >>> import jax, octax_core
        >>> machine = octax_core.Machine("chip8")
        >>> state = machine.boot(bytes([0x12, 0x00]), jax.random.key(0))  # jump-to-self loop
        >>> state = machine.run_frames(state, 0, 2)
        >>> int(state.pc)
        512
    """

    quirks: Union[Quirks, str] = "chip8"
    instructions_per_frame: int = 11

    def __post_init__(self):
        object.__setattr__(self, "quirks", resolve_quirks(self.quirks))
        ipf = self.instructions_per_frame
        if isinstance(ipf, bool) or not isinstance(ipf, int) or ipf <= 0:
            raise ValueError(f"instructions_per_frame must be a positive int, got {ipf!r}")

    def boot(self, rom: RomLike, key: jax.Array) -> MachineState:
        """A powered-on machine with `rom` loaded at 0x200; the key seeds CXNN.

        Jittable and vmappable over `key` (the ROM is baked in as a constant).
        """
        return boot_state(Rom.load(rom), key)

    def execute(self, state: MachineState, keys) -> MachineState:
        """Runs exactly one instruction (no timer tick, no display wait)."""
        new_state, _ = cpu.execute(self.quirks, state, keys_to_mask(keys))
        return new_state

    def run_frames(self, state: MachineState, keys, frames: int) -> MachineState:
        """Runs `frames` 60 Hz frames with `keys` held throughout.

        Args:
            state: one machine (vmap for a batch).
            keys: bool[16] or an integer mask, bit k = key k.
            frames: how many frames; a Python int (static under jit).
        """
        try:
            frames = operator.index(frames)
        except TypeError:
            raise TypeError(
                f"frames must be a Python int (mark it static under jit), got {type(frames).__name__}"
            ) from None
        if frames < 0:
            raise ValueError(f"frames must be >= 0, got {frames}")
        mask = keys_to_mask(keys)

        def frame(state, _):
            return cpu.run_frame(self.quirks, self.instructions_per_frame, state, mask), None

        state, _ = jax.lax.scan(frame, state, None, length=frames)
        return state
