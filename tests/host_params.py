"""Network params drawn on the host, in the shapes a flax init makes: for tests whose point holds
for any params (a file plays as its network plays them; one-by-one is exact where vmap is not),
so that no init program is compiled, only traced by `jax.eval_shape`."""

from __future__ import annotations

import jax
import numpy as np


def fill_like(shapes, seed: int, batch: tuple[int, ...] = ()):
    """Random arrays in the shapes and dtypes of `shapes` (a tree of `jax.ShapeDtypeStruct`, as
    `jax.eval_shape(network.init, ...)` gives), with leading axes `batch`: kernels at flax's init
    scale (1 / sqrt(fan-in)), biases at 0.1."""
    rng = np.random.default_rng(seed)

    def fill(leaf):
        scale = 1 / np.sqrt(np.prod(leaf.shape[:-1])) if len(leaf.shape) > 1 else 0.1
        return (scale * rng.standard_normal((*batch, *leaf.shape))).astype(leaf.dtype)

    return jax.tree.map(fill, shapes)
