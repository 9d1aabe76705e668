"""The instruction is traced once per process for a platform and its fixed quirks
(`frame._execute`), whatever program runs the machine: one machine, a batch of any size."""

import jax
import jax.numpy as jnp

import octax_core
from octax_core.emulator import cpu
from octax_core.emulator.quirks import Quirks

# A quirk set no other test uses, so that no earlier test of the process has traced it already.
RARE = Quirks(vf_reset=True, memory_increment=False, display_wait=False, clipping=False,
              shift_uses_vy=False, jump_uses_vx=True)
LOOP = bytes([0x60, 0x05, 0x70, 0x01, 0x12, 0x02])  # V0 = 5, then V0 += 1 forever


def test_every_program_of_a_machine_reuses_one_trace_of_the_instruction(monkeypatch):
    traced = []
    real = cpu.execute

    def counting(platform, quirks, *args):
        traced.append(quirks)
        return real(platform, quirks, *args)

    monkeypatch.setattr(cpu, "execute", counting)
    machine = octax_core.Machine("schip", quirks=RARE, instructions_per_frame=7)
    keys = jnp.zeros((), jnp.uint32)
    # Traced, not compiled: the programs' shapes are enough (their results are other tests' job).
    one = jax.eval_shape(lambda k: machine.boot(LOOP, k), jax.random.key(0))
    programs = [(lambda s: machine.run_frames(s, keys, 2), one),
                (lambda s: machine.run_frames(s, keys, 3, record_screens=True), one)]
    for n in (3, 5):
        batch = jax.eval_shape(jax.vmap(lambda k: machine.boot(LOOP, k)), jax.random.split(jax.random.key(0), n))
        programs.append((jax.vmap(lambda s: machine.run_frames(s, keys, 2)), batch))
    for program, state in programs:
        jax.jit(program).trace(state)
    assert traced == [RARE]
