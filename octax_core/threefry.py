"""Threefry's CPU lowering, unrolled: the same hash, compiled into fewer kernels.

JAX draws every random number (`jax.random.split`, `uniform`, `randint`, ...) with the
Threefry-2x32 hash, and on CPU it lowers the hash's 20 rounds as a loop of 5 iterations. XLA:CPU
compiles a loop's body, its condition and the code on either side of it as separate kernels,
each an LLVM module of its own, and an env step draws with it two to four times (the key split,
the sticky action, the autoreset's start). Unrolled, as JAX lowers it on GPU, the rounds are
adds, rotations and xors that fuse with the code around them, so the env's programs have fewer
kernels to compile (measured: docs/machine-log.md). The numbers drawn are the same bits: it is
the same hash in exact uint32 arithmetic, looped or not (tests/core_env/test_threefry.py checks
it against a NumPy Threefry-2x32 and against JAX's own loop).

A lowering rule belongs to the process, not to a program: once `octax_core` is imported, every
program lowered for the CPU in that process, the user's own among them, hashes with the unrolled
form. ``OCTAX_ROLLED_THREEFRY=1`` before the import keeps JAX's loop.
"""

from __future__ import annotations

import os

import numpy as np
from jax import lax
from jax.extend.random import threefry2x32_p
from jax.interpreters import mlir

ENV_VAR = "OCTAX_ROLLED_THREEFRY"

# Threefry-2x32's rotation amounts, the first four rounds' and the next four's, alternating; and the
# constant its third key word is xored with (Salmon et al., SC 2011; Random123's threefry.h).
ROTATIONS = ((13, 15, 26, 6), (17, 29, 16, 24))
KEY_PARITY = np.uint32(0x1BD11BDA)


def threefry2x32(key1, key2, x1, x2):
    """Threefry-2x32 with its 20 rounds unrolled: the hash of the uint32 words (x1, x2) under the key
    (key1, key2), all of one shape. Five groups of four rounds (add, rotate left, xor), a key
    injection after each."""
    keys = (key1, key2, key1 ^ key2 ^ KEY_PARITY)
    x1, x2 = x1 + keys[0], x2 + keys[1]
    for group in range(5):
        for rotation in ROTATIONS[group % 2]:
            x1 = x1 + x2
            x2 = lax.shift_left(x2, np.uint32(rotation)) | lax.shift_right_logical(x2, np.uint32(32 - rotation))
            x2 = x1 ^ x2
        x1 = x1 + keys[(group + 1) % 3]
        x2 = x2 + keys[(group + 2) % 3] + np.uint32(group + 1)
    return x1, x2


_UNROLLED = mlir.lower_fun(threefry2x32, multiple_results=True)


def install() -> None:
    """Lowers `threefry2x32_p` unrolled on CPU, in this process, from now on (programs compiled
    before keep theirs; a cached program is keyed by its HLO, so it is never mistaken for the
    other form)."""
    mlir.register_lowering(threefry2x32_p, _UNROLLED, platform="cpu")


def apply_environment() -> None:
    """`install()`, unless ``OCTAX_ROLLED_THREEFRY`` is set to 1 (JAX's rolled loop kept)."""
    value = os.environ.get(ENV_VAR, "")
    if value not in ("", "0", "1"):
        raise ValueError(f"{ENV_VAR} must be 0 or 1 (1 keeps JAX's rolled Threefry loop on CPU), got {value!r}")
    if value != "1":
        install()
