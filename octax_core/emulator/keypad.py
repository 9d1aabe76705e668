"""Keypad input: the two accepted forms, checked and turned into one uint32 mask."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np


def keys_to_mask(keys) -> jax.Array:
    """bool[16] (key k held at index k) or an integer mask (bit k = key k) -> uint32 mask.

    Raises:
        ValueError: a bool array whose last axis is not 16, or a concrete integer mask outside
            0..0xFFFF.
        TypeError: any other dtype.
    """
    array = jnp.asarray(keys)
    if array.dtype == jnp.bool_:
        if array.shape[-1:] != (16,):
            raise ValueError(f"a bool key array must have 16 entries (one per key), got shape {array.shape}")
        weights = jnp.left_shift(jnp.uint32(1), jnp.arange(16, dtype=jnp.uint32))
        return jnp.sum(jnp.where(array, weights, jnp.uint32(0)), axis=-1, dtype=jnp.uint32)
    if not jnp.issubdtype(array.dtype, jnp.integer):
        raise TypeError(f"keys must be a bool[16] array or an integer bit mask, got dtype {array.dtype}")
    if not isinstance(keys, jax.core.Tracer):
        concrete = np.asarray(keys)
        if concrete.size and (concrete.min() < 0 or concrete.max() > 0xFFFF):
            raise ValueError(f"a key mask must be in 0..0xFFFF (bit k = key k), got {concrete.min()}..{concrete.max()}")
    return array.astype(jnp.uint32)
