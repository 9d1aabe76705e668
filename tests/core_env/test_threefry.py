"""The unrolled Threefry lowering (octax_core/threefry.py): the hash's own bits, fewer kernels than
JAX's rolled loop, and every draw an env makes the same as under JAX's loop.

The reference is Threefry-2x32 with 20 rounds written here in NumPy from its definition (Salmon et
al., "Parallel random numbers: as easy as 1, 2, 3", SC 2011), checked against Random123's known
answers, so it depends on neither lowering.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import jax
import numpy as np
import pytest
from jax.extend.random import threefry_2x32

from octax_core import threefry

ROTATIONS = ((13, 15, 26, 6), (17, 29, 16, 24))

# Random123's known answers for Threefry-2x32-20: (key, counter, result)
KNOWN = [((0x00000000, 0x00000000), (0x00000000, 0x00000000), (0x6B200159, 0x99BA4EFE)),
         ((0xFFFFFFFF, 0xFFFFFFFF), (0xFFFFFFFF, 0xFFFFFFFF), (0x1CB996FC, 0xBB002BE7)),
         ((0x13198A2E, 0x03707344), (0x243F6A88, 0x85A308D3), (0xC4923A9C, 0x483DF7A0))]


def reference(key, x1: np.ndarray, x2: np.ndarray):
    """Threefry-2x32-20 of the words (x1, x2) under key (k0, k1), in uint32 NumPy."""
    with np.errstate(over="ignore"):
        k0, k1 = np.uint32(key[0]), np.uint32(key[1])
        k = (k0, k1, k0 ^ k1 ^ np.uint32(0x1BD11BDA))
        a, b = x1 + k[0], x2 + k[1]
        for group in range(5):
            for r in ROTATIONS[group % 2]:
                a = a + b
                b = (b << np.uint32(r)) | (b >> np.uint32(32 - r))
                b = a ^ b
            a = a + k[(group + 1) % 3]
            b = b + k[(group + 2) % 3] + np.uint32(group + 1)
    return a, b


@pytest.mark.parametrize("key, counter, result", KNOWN)
def test_the_reference_gives_random123s_known_answers(key, counter, result):
    a, b = reference(key, np.uint32([counter[0]]), np.uint32([counter[1]]))
    assert (int(a[0]), int(b[0])) == result


def test_jitted_threefry_on_cpu_is_the_reference_hash():
    rng = np.random.default_rng(0)
    hash_all = jax.jit(threefry_2x32)
    for size in (2, 6, 64):  # JAX hashes the count's first half as x1 and its second as x2
        key = rng.integers(0, 2**32, 2, dtype=np.uint32)
        count = rng.integers(0, 2**32, size, dtype=np.uint32)
        a, b = reference(key, count[:size // 2], count[size // 2:])
        np.testing.assert_array_equal(np.asarray(hash_all(key, count)), np.concatenate([a, b]))
    for key, counter, result in KNOWN:
        assert tuple(int(w) for w in hash_all(np.uint32(key), np.uint32(counter))) == result


def test_the_unrolled_form_is_what_a_cpu_program_compiles():
    """JAX's rolled form is a while loop in the compiled program; the unrolled one is none."""
    split = jax.jit(lambda key: jax.random.split(key, 4)).lower(jax.random.key(0)).compile().as_text()
    assert "while" not in split.lower()


DRAWS = """
import hashlib, json
import jax, numpy as np
import octax_core
def draws(seed):
    key = jax.random.key(seed)
    a, b = jax.random.split(key)
    return (jax.random.key_data(jax.random.split(key, (3, 5))), jax.random.uniform(a, (7,)),
            jax.random.randint(b, (4, 3), 0, 18), jax.random.normal(a, (2, 2)), jax.random.bits(b, (9,), np.uint8),
            jax.random.split(jax.random.PRNGKey(seed)), jax.random.key_data(jax.random.fold_in(key, 7)))
out = [np.asarray(x) for seed in (0, 1, 2**31 - 1) for x in jax.jit(draws, static_argnums=0)(seed)]
split = jax.jit(lambda k: jax.random.split(k, 4)).lower(jax.random.key(0)).compile().as_text()
print(json.dumps({"hash": hashlib.sha1(b"".join(x.tobytes() for x in out)).hexdigest(),
                  "while": "while" in split.lower()}))
"""


ROLLOUT = """
import hashlib, json
import jax, numpy as np
import octax_core
env, params = octax_core.make("Pong", autoreset=True, noop_max=3, repeat_action_probability=0.25)
keys = jax.random.split(jax.random.key(5), 3)
obs, state = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
def body(state, key):
    actions = jax.random.randint(key[0], (3,), 0, env.num_actions)
    obs, state, reward, terminated, truncated, info = jax.vmap(env.step, in_axes=(0, 0, 0, None))(
        key, state, actions, params)
    return state, (obs, reward, terminated, truncated, info, jax.random.uniform(key[1], (2,)))
final, out = jax.jit(lambda s: jax.lax.scan(body, s, jax.random.split(jax.random.key(9), (12, 3))))(state)
def raw(x):
    return np.asarray(jax.random.key_data(x) if jax.dtypes.issubdtype(x.dtype, jax.dtypes.prng_key) else x)
digest = hashlib.sha1(b"".join(raw(x).tobytes() for x in jax.tree.leaves((obs, out, final))))
split = jax.jit(lambda k: jax.random.split(k, 4)).lower(jax.random.key(0)).compile().as_text()
print(json.dumps({"hash": digest.hexdigest(), "while": "while" in split.lower()}))
"""


def run_in_a_process(program: str, rolled: bool) -> dict:
    """What `program` prints, run in a fresh process with JAX's loop or the unrolled form."""
    env = {**os.environ, threefry.ENV_VAR: "1" if rolled else "0"}
    result = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, env=env, timeout=300)
    assert result.returncode == 0, result.stderr[-3000:]
    return json.loads(result.stdout.splitlines()[-1])


def run_here(program: str) -> dict:
    """What `program` prints, run in this process (the unrolled form)."""
    printed: list = []
    exec(program, {"print": printed.append})
    return json.loads(printed[0])


def test_every_kind_of_draw_is_the_same_bits_under_jaxs_loop():
    """Splits (typed and raw keys), uniform, randint, normal, bits and fold_in, jitted: the opt-out's
    process (JAX's rolled loop) and this one (unrolled) draw the same bits."""
    rolled = run_in_a_process(DRAWS, rolled=True)
    assert rolled["while"]  # the opt-out keeps JAX's loop
    assert run_here(DRAWS) == {"hash": rolled["hash"], "while": False}


@pytest.mark.slow  # an env program compiled in each form (a fresh process for JAX's loop): about 10 s on 2 cores
def test_an_env_rollout_draws_the_same_bits_under_jaxs_loop():
    """Sticky actions, no-op starts and autoresets all draw keys: the rollout under JAX's rolled
    loop (the opt-out) is bit for bit the rollout under the unrolled form (this process's)."""
    rolled = run_in_a_process(ROLLOUT, rolled=True)
    assert rolled["while"]
    assert run_here(ROLLOUT) == {"hash": rolled["hash"], "while": False}


@pytest.mark.parametrize("value", ["yes", "2", " 1"])
def test_a_bad_opt_out_value_is_named(value, monkeypatch):
    monkeypatch.setenv(threefry.ENV_VAR, value)
    with pytest.raises(ValueError, match=r"OCTAX_ROLLED_THREEFRY must be 0 or 1 .* got " + repr(value)):
        threefry.apply_environment()
