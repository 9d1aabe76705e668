"""A dataset as flat arrays of transitions, and minibatches drawn from them without a loop per step.

    from octax_gym.datasets import load_transitions
    data = load_transitions("octax/Brix-random-v0")           # numpy, in memory
    batch = data.sample(np.random.default_rng(0), 256)        # Batch(obs, action, reward, next_obs, ...)

    data = data.device_put()                                  # the same arrays on JAX's device
    batch = data.sample(jax.random.key(0), 256)               # inside jit and lax.scan too

Each episode's T + 1 observations are stored once, one episode after another, and a transition
holds the row of its observation (`obs_index`); the next observation is the row after it, so a
dataset takes the memory of its observations once, not twice. Sampling is one gather: draw
transition indices, then index every array with them (numpy on the host, `jnp.take` in a jitted
program). `Transitions` is a NamedTuple, so a JAX pytree: pass it into jitted functions as an
argument, never close over it (that would bake the whole dataset into the program as a constant).
"""

from __future__ import annotations

from typing import NamedTuple, Optional, Sequence

import numpy as np


class Batch(NamedTuple):
    """A minibatch of transitions; every field has the batch as its first axis."""

    obs: np.ndarray  # (B, *observation shape) uint8
    action: np.ndarray  # (B,) int32
    reward: np.ndarray  # (B,) float32
    next_obs: np.ndarray  # (B, *observation shape) uint8: the observation after the action
    terminated: np.ndarray  # (B,) bool: the episode ended there (no bootstrapping from next_obs)
    truncated: np.ndarray  # (B,) bool: cut there (time limit or end of collection); next_obs is real

    @property
    def done(self):
        """The flag a value target stops at: terminated (a truncation is not the game's end)."""
        return self.terminated


class Transitions(NamedTuple):
    """Every transition of a dataset (or of the episodes asked for), as flat arrays.

    Transition i goes from `observations[obs_index[i]]` to `observations[obs_index[i] + 1]`.
    """

    observations: np.ndarray  # (episodes + transitions, *obs shape): each episode's T + 1 in order
    obs_index: np.ndarray  # (N,) int32
    actions: np.ndarray  # (N,) int32
    rewards: np.ndarray  # (N,) float32
    terminations: np.ndarray  # (N,) bool
    truncations: np.ndarray  # (N,) bool
    episode_ids: np.ndarray  # (N,) int32: the dataset's episode id of each transition

    def __len__(self) -> int:
        return int(self.actions.shape[0])

    def batch(self, indices) -> Batch:
        """The transitions at `indices` (numpy or JAX integers, any shape)."""
        rows = self.obs_index[indices]
        return Batch(self.observations[rows], self.actions[indices], self.rewards[indices],
                     self.observations[rows + 1], self.terminations[indices], self.truncations[indices])

    def sample(self, rng, batch_size: int) -> Batch:
        """`batch_size` transitions drawn uniformly with replacement: from a numpy Generator on the
        host, or from a JAX key (traceable: use it inside jit on `device_put()` data)."""
        if isinstance(rng, np.random.Generator):
            return self.batch(rng.integers(0, len(self), batch_size))
        import jax

        return self.batch(jax.random.randint(rng, (batch_size,), 0, self.actions.shape[0]))

    def device_put(self, device=None) -> "Transitions":
        """The same transitions as JAX arrays on `device` (JAX's default device if None)."""
        import jax

        return jax.device_put(self, device)


def load_transitions(dataset, episode_indices: Optional[Sequence[int]] = None) -> Transitions:
    """Reads a Minari dataset (a `MinariDataset` or its id) into flat `Transitions`.

    One pass over the episodes with one open of the file (Minari's storage reader), each episode
    copied into arrays sized from the metadata beforehand: no concatenation, no loop per step.
    `episode_indices` picks episodes (in that order); by default every episode.
    """
    if isinstance(dataset, str):
        from octax_gym.datasets.storage import import_minari

        dataset = import_minari().load_dataset(dataset)
    if episode_indices is None:
        episode_indices = list(dataset.episode_indices)
        num_steps = dataset.total_steps
    else:
        episode_indices = [int(i) for i in episode_indices]
        num_steps = sum(int(m["total_steps"]) for m in dataset.storage.get_episode_metadata(episode_indices))
    num_obs = num_steps + len(episode_indices)
    space = dataset.observation_space
    out = Transitions(np.empty((num_obs, *space.shape), space.dtype), np.empty(num_steps, np.int32),
                      np.empty(num_steps, np.int32), np.empty(num_steps, np.float32),
                      np.empty(num_steps, np.bool_), np.empty(num_steps, np.bool_), np.empty(num_steps, np.int32))
    row = step = 0
    for episode in dataset.storage.get_episodes(episode_indices):
        steps = len(episode["actions"])
        out.observations[row:row + steps + 1] = episode["observations"]
        out.obs_index[step:step + steps] = np.arange(row, row + steps)
        out.actions[step:step + steps] = episode["actions"]
        out.rewards[step:step + steps] = episode["rewards"]
        out.terminations[step:step + steps] = episode["terminations"]
        out.truncations[step:step + steps] = episode["truncations"]
        out.episode_ids[step:step + steps] = episode["id"]
        row, step = row + steps + 1, step + steps
    if step != num_steps or row != num_obs:
        raise ValueError(f"dataset {dataset.spec.dataset_id!r}: its metadata counts {num_steps} steps in "
                         f"{len(episode_indices)} episodes but its episodes hold {step}")
    return out

