"""One batch of envs over many devices, and over many processes: which lanes are whose, and the
moves between a process's own lanes and the global batch the jitted step runs on.

`OctaxVectorEnv(game, N, devices="all")` (and `gymnasium.make_vec(..., devices="all")`) builds a
1-D device mesh with the axis "envs" over the given devices and shards the batch of N envs along
it, lane block by lane block in device order. The env's step stays one jitted call, now on global
arrays: XLA partitions the batched step over the devices (each runs its own lanes), and the few
batch-wide decisions in it (a `lax.cond` taken when any lane needs it) become collectives. In a
multi-process run (`octax_gym.step.distributed.initialize`, then every process makes the same env), each
process feeds and reads only the lanes on its own devices: `env.num_envs` is that count,
`env.global_env_ids` their indices in the global batch, and global env i is seeded `seed + i`
whatever the process count, so it plays exactly as `gymnasium.make` seeded `seed + i`.

With one local device per process (a GPU each, the usual multi-host layout) a process's lanes are
one shard on its device, handed to numpy, JAX or torch without a copy, as on one device; with
several local devices they are gathered onto the first.
"""

from __future__ import annotations

from typing import Any, Sequence

import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from octax_gym.step import backends

AXIS = "envs"


class Shards:
    """The lanes of a batch of `num_envs` sharded over `devices` along the mesh axis "envs".

    Args:
        devices: "all" (every device of every process, `jax.devices()`), a sequence of devices
            (`jax.Device`s or names backends.resolve_device knows: "cpu:0", "cuda:1"), or a
            `jax.sharding.Mesh` with an axis named "envs" (the batch is split along it and
            replicated along any other).

    Raises:
        ValueError: the batch does not divide over the devices, a mesh without the "envs" axis,
            no devices, or a device named twice.
    """

    def __init__(self, devices: Any, num_envs: int):
        self.mesh = _mesh(devices)
        size = self.mesh.shape[AXIS]
        if num_envs % size:
            raise ValueError(f"num_envs={num_envs} does not divide over the {size} devices of the mesh's "
                             f"'{AXIS}' axis; use a multiple of {size}")
        self.global_num_envs = num_envs
        self.batch = NamedSharding(self.mesh, PartitionSpec(AXIS))
        self.replicated = NamedSharding(self.mesh, PartitionSpec())
        blocks = sorted({(s[0].start or 0, s[0].stop if s[0].stop is not None else num_envs): d
                         for d, s in self.batch.addressable_devices_indices_map((num_envs,)).items()}.items())
        self.local_devices = [device for _, device in blocks]
        self.global_env_ids = np.concatenate([np.arange(start, stop) for (start, stop), _ in blocks])
        if len(np.unique(self.global_env_ids)) != len(self.global_env_ids):  # a mesh replicating lanes here
            raise ValueError(f"the mesh gives this process the same lanes on several devices; split the "
                             f"batch along '{AXIS}' only over the devices that hold distinct lanes")
        self.num_local = len(self.global_env_ids)
        self.device = self.local_devices[0]

    def partitioned(self, fn, compiler_options=None):
        """`fn` (a batched step or reset, unjitted: JAX takes `compiler_options` on the outermost
        jit only) jitted with its batched outputs constrained to the batch sharding, so each
        device computes and keeps its own lanes (left to itself, XLA's propagation may replicate
        an output on every device)."""
        def constrain(x):
            if isinstance(x, jax.Array) and x.ndim and x.shape[0] == self.global_num_envs:
                return jax.lax.with_sharding_constraint(x, self.batch)
            return x

        return jax.jit(lambda *args: jax.tree.map(constrain, fn(*args)), compiler_options=compiler_options)

    def to_global(self, local) -> jax.Array:
        """This process's rows (num_local, ...) of a batched array as the global (num_envs, ...) array."""
        local = np.asarray(local)
        return jax.make_array_from_process_local_data(self.batch, local, (self.global_num_envs, *local.shape[1:]))

    def keys(self, local_seeds: Sequence[int]) -> jax.Array:
        """The global batch of typed PRNG keys, `jax.random.key(seed)` for each of this process's lanes."""
        from octax_gym.step.compiled_step import keys_from_seeds

        return jax.random.wrap_key_data(self.to_global(jax.random.key_data(keys_from_seeds(list(local_seeds)))))

    def replicate(self, tree):
        """Every leaf copied whole to every device of the mesh (the env's params)."""
        def leaf(x):
            host = np.asarray(x)
            return jax.make_array_from_callback(host.shape, self.replicated, lambda index: host[index])
        return jax.tree.map(leaf, tree)

    def to_local(self, tree):
        """This process's lanes of every batched leaf: its one shard as it is (no copy), or its
        shards in lane order gathered on its first device. Unbatched leaves are left as they are."""
        def leaf(x):
            if not isinstance(x, jax.Array) or x.ndim == 0 or x.shape[0] != self.global_num_envs:
                return x
            shards = sorted(x.addressable_shards, key=lambda s: s.index[0].start or 0)
            if len(shards) == 1:
                return shards[0].data
            return jax.numpy.concatenate([jax.device_put(s.data, self.device) for s in shards])
        return jax.tree.map(leaf, tree)


def _mesh(devices: Any) -> Mesh:
    if isinstance(devices, Mesh):
        if AXIS not in devices.axis_names:
            raise ValueError(f"the mesh has axes {tuple(devices.axis_names)}; the batch is split along one "
                             f"named '{AXIS}': Mesh(devices, ('{AXIS}',))")
        return devices
    if isinstance(devices, str) and devices == "all":
        found = jax.devices()
    elif isinstance(devices, (list, tuple)) and devices:
        found = [backends.resolve_device(d) for d in devices]
    else:
        raise ValueError(f"devices must be 'all', a non-empty list of devices, or a jax.sharding.Mesh with an "
                         f"axis named '{AXIS}', got {devices!r}")
    if len(set(found)) != len(found):
        raise ValueError(f"devices names a device twice: {found}")
    return Mesh(np.array(found), (AXIS,))
