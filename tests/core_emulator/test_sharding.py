"""The machine runs under `jax.shard_map` with its replication checks on.

Splitting a batch over devices is how the benchmark uses both CPU cores (benchmarks/README.md).
A loop carry that starts as a constant (not batched like the state) breaks shard_map's
varying-axes check; a one-device mesh is enough to catch that, so this needs no XLA flags.
"""

import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec as P

import octax_core

ROM = bytes([0x60, 0x05, 0xF0, 0x15, 0xD0, 0x15, 0x70, 0x01, 0x12, 0x04])  # a few ops and a DXYN loop


def test_run_frames_under_shard_map_matches_vmap():
    machine = octax_core.Machine("chip8")
    states = jax.vmap(lambda k: machine.boot(ROM, k))(jax.random.split(jax.random.key(0), 4))
    step = jax.vmap(lambda s: machine.run_frames(s, 0, 3))
    mesh = Mesh(jax.devices()[:1], ("env",))
    sharded = jax.jit(jax.shard_map(step, mesh=mesh, in_specs=P("env"), out_specs=P("env")))
    placed = jax.device_put(states, NamedSharding(mesh, P("env")))
    expected, got = octax_core.snapshot(jax.jit(step)(states)), octax_core.snapshot(sharded(placed))
    for name in expected:
        np.testing.assert_array_equal(got[name], expected[name], err_msg=name)
