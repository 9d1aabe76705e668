"""The per-opcode test builder: boot a tiny program, set state fields, step instructions.

Used by every tests/core/test_ops_*.py (as in chip8-rust's processor tests: symbolic PCs and a
builder), with the jitted functions coming from the session caches in tests/conftest.py.
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core

START = 0x200
NEXT = START + 2
SKIPPED = START + 4
NO_QUIRKS = dict(vf_reset=False, memory_increment=False, display_wait=False, clipping=False,
                 shift_uses_vy=False, jump_uses_vx=False)
_DTYPES = dict(V=jnp.uint8, I=jnp.uint16, pc=jnp.uint16, sp=jnp.uint8, stack=jnp.uint16,
               delay_timer=jnp.uint8, sound_timer=jnp.uint8, screen=jnp.uint32, rng=jnp.uint32,
               key_wait=jnp.uint8)


def quirks(**on) -> octax_core.Quirks:
    """All six quirks off except those given."""
    return octax_core.Quirks(**{**NO_QUIRKS, **on})


class Chip:
    """A machine booted with `program` (16-bit words) at START, run one instruction at a time.

    Keyword arguments set state fields: `V={x: value}`, `memory={address: bytes}`, and any
    MachineState field by name (`I=0x300`, `sp=15`, ...). Reading `chip.<field>` gives the
    snapshot value (ints for scalars, numpy arrays otherwise). `jit` is the pair of session
    caches (jit_execute, jit_run_frames) from tests/conftest.py.
    """

    def __init__(self, jit, program, quirks="chip8", *, V=(), memory=(), ipf=11, **fields):
        self._jit = jit
        self.machine = octax_core.Machine(quirks=quirks, instructions_per_frame=ipf)
        data = b"".join(word.to_bytes(2, "big") for word in program)
        state = self.machine.boot(data, jax.random.key(0))
        regs = np.asarray(state.V).copy()
        for x, value in dict(V).items():
            regs[x] = value
        fields["V"] = regs
        state = state.replace(**{name: jnp.asarray(v, _DTYPES[name]) for name, v in fields.items()})
        for address, values in dict(memory).items():
            state = octax_core.poke(state, address, bytes(values))
        self.state = state

    def step(self, keys=0, times=1):
        for _ in range(times):
            self.state = self._jit[0](self.machine)(self.state, keys)
        return self

    def frames(self, n, keys=0):
        """Runs n frames, one a call: a config compiles once, and the default configs' program
        is the one test_differential.py and test_vmap.py run."""
        for _ in range(n):
            self.state = self._jit[1](self.machine)(self.state, keys, 1)
        return self

    def snapshot(self):
        return octax_core.snapshot(self.state)

    def __getattr__(self, name):
        if name in ("state", "machine", "_jit"):
            raise AttributeError(name)
        value = self.snapshot()[name]
        return int(value) if value.ndim == 0 else value


@pytest.fixture
def chip(jit_execute, jit_run_frames):
    """The builder: chip(program, quirks="chip8", **fields) -> Chip."""
    return functools.partial(Chip, (jit_execute, jit_run_frames))


def hexid(value):
    """Test ids in hex: 8F24-FF-01-01 rather than 36644-255-1-1."""
    return f"{value:02X}" if isinstance(value, int) and not isinstance(value, bool) else None
