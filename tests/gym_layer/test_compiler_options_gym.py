"""The Gymnasium envs' jitted step and reset are compiled with the game's platform options
(`Platform.compiler_options`, exact by tests/core_emulator/test_compiler_options.py)."""

from __future__ import annotations

import re

import jax
import jax.numpy as jnp

from gymnasium.vector import AutoresetMode

import octax_core
from octax_gym.step import action_check
from octax_gym.step.compiled_step import CompiledStep

NUM_ENVS = 3


def _copies(compiled) -> int:
    return len(re.findall(r"\bcopy\(", compiled.as_text()))


def test_the_gym_step_is_compiled_with_the_platform_options():
    """The envs' step drops the loop's register copies that a plain jit of the same function keeps."""
    env, params = octax_core.make("Carbon8", autoreset=False)
    assert env.compiler_options, "chip8 is measured faster with region analysis"
    step = CompiledStep(env)
    keys = jax.random.split(jax.random.key(0), NUM_ENVS)
    keys, obs, state, _ = step.reset(keys, None, None, None, params)
    args = (keys, state, jnp.zeros(NUM_ENVS, jnp.int32), jnp.asarray(action_check.NO_REPORT, jnp.int32), params)
    mode = AutoresetMode.NEXT_STEP
    shipped = step.step[mode].lower(*args).compile()
    plain = jax.jit(step.step_fns[mode], donate_argnums=(1,)).lower(*args).compile()
    assert _copies(shipped) < _copies(plain)
