"""Each platform's XLA compile options (`Platform.compiler_options`): exact, and really passed.

The options change how XLA:CPU places buffers (region-analysis copy insertion drops the loop's
register copies), never what a program computes. These tests hold that to the bit: an archive game
of the smallest and of the largest platform, stepped by a vmapped env (with autoreset) under random
actions, gives the same observations, rewards, flags, info and machine state compiled plainly and
compiled with the options, and with region analysis forced on where the platform leaves it off. (CHIP-8's loop
has the fewest buffers; XO-CHIP's has every SUPER-CHIP opcode, gate and buffer, plus plane 2 and
64 KiB: a SUPER-CHIP game would compile two more programs to check a subset of XO-CHIP's.)
tests/gym_layer/test_compiler_options_gym.py checks that the options reach the compiles that ship.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from core_shared import ROLLOUT_ENVS, ROLLOUT_STEPS, env_rollout, rollout_of

import octax_core
from octax_core.emulator.platforms import PLATFORMS

REGION_ANALYSIS = {"xla_cpu_copy_insertion_use_region_analysis": True}
# An archive game of the smallest and the largest platform (they ship in the package: no ../shared
# needed), with autoreset: Civiliz8n's plain rollout is tests/core_env/test_skip_idle_envs.py's
# skipping one (one program for both, through tests/core_shared.py).
GAMES = {"chip8": "Carbon8", "xochip": "Civiliz8n"}


def _plain(tree):
    return [np.asarray(jax.random.key_data(x) if jnp.issubdtype(x.dtype, jax.dtypes.prng_key) else x)
            for x in jax.tree.leaves(tree)]


@pytest.mark.parametrize("platform", sorted(GAMES))
def test_every_step_is_the_same_with_the_options(platform):
    env, params, jitted = env_rollout(GAMES[platform], autoreset=True, skip_idle=True)
    assert env.machine.platform.name == platform
    keys = jax.random.split(jax.random.key(7), (ROLLOUT_STEPS + 1, ROLLOUT_ENVS))
    actions = np.random.default_rng(8).integers(0, env.num_actions, (ROLLOUT_STEPS, ROLLOUT_ENVS), dtype=np.int32)
    plain = jitted(keys, actions)  # (reset obs, (obs, reward, terminated, truncated, info), final state)
    # The platform's options and region analysis forced on: each distinct, non-plain set once
    # (every platform's own are region analysis today, so one set).
    option_sets = [env.compiler_options] if env.compiler_options else []
    option_sets += [o for o in ({**env.compiler_options, **REGION_ANALYSIS},) if o not in option_sets]
    for options in option_sets:
        tuned = jax.jit(rollout_of(env, params), compiler_options=options)(keys, actions)
        assert jax.tree.structure(tuned) == jax.tree.structure(plain)
        for a, b in zip(_plain(plain), _plain(tuned)):
            np.testing.assert_array_equal(a, b, err_msg=f"{platform} with {options}")
    # The rollout did something: the screens changed.
    screens = np.asarray(plain[1][0])
    assert screens.shape[:2] == (ROLLOUT_STEPS, ROLLOUT_ENVS) and (screens[0] != screens[-1]).any()


def test_the_options_are_the_platforms_and_pass_through_machine_and_env():
    for platform in PLATFORMS.values():
        options = platform.compiler_options
        assert isinstance(options, dict) and options == dict(platform.xla_options)
        assert octax_core.Machine(platform.name).compiler_options == options
    env, _ = octax_core.make(GAMES["xochip"])
    assert env.compiler_options == PLATFORMS["xochip"].compiler_options
    # Every option is one XLA knows: a misspelt name fails the compile.
    for platform in PLATFORMS.values():
        jax.jit(lambda x: x + 1, compiler_options=platform.compiler_options)(jnp.int32(1))
    with pytest.raises(Exception, match="No such compile option"):
        jax.jit(lambda x: x + 1, compiler_options={"xla_cpu_no_such_option": True})(jnp.int32(2))
