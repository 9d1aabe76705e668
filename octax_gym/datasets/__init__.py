"""Offline RL datasets: collect them exactly and compactly as Minari datasets, load them as flat
transitions, and build the dataset suite.

    from octax_gym.datasets import collect_dataset, episode_seed, load_transitions
    result = collect_dataset("Brix", "octax/Brix-random-v0", num_steps=100_000, num_envs=64)
    data = load_transitions(result.dataset)                 # or load_transitions("octax/Brix-random-v0")
    batch = data.sample(np.random.default_rng(0), 256)

- `collect`: many lanes stepped in one jitted call, every episode with the seed that replays it.
- `storage`: Minari's HDF5 layout written with HDF5's own compression filters (~125 bytes a
  CHIP-8 step instead of ~9,400), read back bit for bit by `minari.load_dataset`.
- `transitions`: the loader and minibatch sampler (numpy, or JAX inside jit).
- `suite`: the dataset suite (octax/<Game>/random|medium|expert-v0) from trained PPO policies.
- `diskwrite`: HDF5 written so that a full disk is a `DatasetWriteError` (an OSError), not a crash.
- `damage`: a damaged dataset folder as a `DamagedDatasetError` (a ValueError) naming the file.

Minari is the optional `datasets` extra, imported inside the functions: `import octax_gym.datasets`
works without it. See docs/datasets.md.
"""

import importlib

# Imported on first use, so `octax_gym.datasets.suite`'s names (the CLI's choices) come without JAX.
_EXPORTS = {
    "CollectResult": "collect", "FLUSH_STEPS": "collect", "collect_dataset": "collect", "episode_seed": "collect",
    "recovery_spec": "collect",
    "DatasetWriter": "storage", "EpisodeRecord": "storage", "INSTALL_HINT": "storage", "finish_dataset": "storage",
    "Batch": "transitions", "Transitions": "transitions", "load_transitions": "transitions",
    "build_suite": "suite", "pick_policies": "suite",
    "combine_datasets": "combine", "shard_plan": "combine",
    "DatasetWriteError": "diskwrite", "DamagedDatasetError": "damage",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'octax_gym.datasets' has no attribute {name!r}")
    return getattr(importlib.import_module(f"octax_gym.datasets.{_EXPORTS[name]}"), name)


def __dir__():
    return sorted([*globals(), *_EXPORTS])
