"""Data-parallel placement of a run (`devices="all"`): every agent's envs split over every device.

A 1-D mesh "envs" over every device of every process; the runner's env states, observations and
running returns (axis 1, after the agent axis) are split along it, everything else (params,
optimizer state, keys, games) replicated. The update is compiled with these shardings, so XLA runs
each device's envs where they live and averages the loss, hence the gradients, over the whole
batch with its own collectives: the algorithm's code is unchanged, and the params are those of
one device up to the order of float sums.
"""

from __future__ import annotations

import jax
import numpy as np

from octax_gym.train.checkpoints import host_values, is_key, keys_as_data
from octax_gym.train.config import TrainConfig


class DataParallel:
    BATCH_FIELDS = ("env_state", "obs", "episode_return")

    def __init__(self, config: TrainConfig):
        from jax.sharding import Mesh, NamedSharding, PartitionSpec

        self.mesh = Mesh(np.array(jax.devices()), ("envs",))
        if config.num_envs % self.mesh.size:
            raise ValueError(f"num_envs={config.num_envs} does not divide over the {self.mesh.size} devices "
                             f"(devices='all'); use a multiple of {self.mesh.size}")
        self.batch = NamedSharding(self.mesh, PartitionSpec(None, "envs"))
        self.replicated = NamedSharding(self.mesh, PartitionSpec())

    def shardings(self, runner):
        fields = {name: jax.tree.map(lambda _: self.batch if name in self.BATCH_FIELDS else self.replicated,
                                     getattr(runner, name)) for name in runner._fields}
        return type(runner)(**fields)

    def place(self, runner):
        """The runner (the same values on every process) as global arrays with `shardings`."""
        shardings = self.shardings(runner)
        host = host_values(keys_as_data(runner))
        placed = jax.tree.map(lambda x, s: jax.make_array_from_callback(np.shape(x), s, lambda i: np.asarray(x)[i]),
                              host, shardings)
        return jax.tree.map(lambda t, x: jax.random.wrap_key_data(x, impl=jax.random.key_impl(t)) if is_key(t) else x,
                            runner, placed)

    def replicate(self, tree):
        """Host values (keys included) replicated on every device."""
        def one(x):
            data = np.asarray(jax.random.key_data(x)) if is_key(x) else np.asarray(x)
            placed = jax.make_array_from_callback(data.shape, self.replicated, lambda i: data[i])
            return jax.random.wrap_key_data(placed, impl=jax.random.key_impl(x)) if is_key(x) else placed
        return jax.tree.map(one, tree)
