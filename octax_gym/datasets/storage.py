"""Writing a Minari dataset compactly: Minari's own HDF5 layout, with HDF5's compression filters.

A CHIP-8 observation is four 32 x 64 frames of 0/1 bytes: 8 KB a step, which Minari 0.5's HDF5
storage writes as it is (its writer takes no filter). Over 99% of those bytes are zeros or repeat
the frame before, so the observations here go through two filters that every HDF5 reader applies
by itself on read (libhdf5 ships both): scale-offset, which stores each integer in the fewest bits
its chunk needs (1 bit for 0/1 pixels, 2 for XO-CHIP's four colours; lossless for integers), then
deflate (gzip). The rest of an episode (actions, rewards, flags, infos) is a few bytes a step,
stored plain.

The file is Minari's: the same groups (`episode_<id>` with its `id`, `seed` and `total_steps`
attributes; `observations`, `actions`, `rewards`, `terminations`, `truncations`; `infos/...`),
the same metadata.json, `data_format: "hdf5"`, so `minari.load_dataset` and any HDF5 tool read it
unchanged and bit for bit: nothing here to decode. The metadata's `observation_filters` says how
the observations are stored. Brix random play: 9,377 bytes a step written by Minari, about 125
here (benchmarks/datasets.py).

Episodes are appended with h5py in groups of at least `flush_steps` steps (memory holds one group),
and the metadata's totals are updated after each group, so a dataset interrupted between groups is
still a readable dataset of the episodes written so far.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any, Optional

import numpy as np

INSTALL_HINT = 'pip install "octax-gym[datasets]"'

# h5py's create_dataset filter arguments for the observations. scaleoffset=0: the fewest bits each
# chunk's integers need, found per chunk; deflate level 1 compresses within a few percent of level 9
# at several times its speed on these frames (benchmarks/datasets.py).
OBSERVATION_FILTERS = {"scaleoffset": 0, "compression": "gzip", "compression_opts": 1}
FILTERS_NAME = "scaleoffset+gzip1"
CHUNK_STEPS = 64  # observations per HDF5 chunk (the unit compressed and read back together)
# HDF5's newest object formats: smaller per-dataset headers and chunk indexes than the 1.8-compatible
# default, which matters for short episodes (a random Brix episode is 33 steps). HDF5 >= 1.10 reads it.
LIBVER = "latest"


class EpisodeRecord:
    """One episode as it is played: its reset seed and what the env returned since that reset,
    numpy rows copied out of their batch (so the batch can be freed)."""

    def __init__(self, seed: int, obs: np.ndarray, info: dict[str, Any]):
        self.seed = seed
        self.observations = [np.array(obs, copy=True)]
        self.infos = {name: [value] for name, value in info.items()}
        self.actions, self.rewards, self.terminations, self.truncations = [], [], [], []

    def add(self, action, obs, reward, terminated, truncated, info: dict[str, Any]) -> None:
        self.actions.append(action)
        self.observations.append(np.array(obs, copy=True))
        self.rewards.append(reward)
        self.terminations.append(terminated)
        self.truncations.append(truncated)
        for name, value in info.items():
            self.infos[name].append(value)

    @classmethod
    def from_stored(cls, seed: int, episode: dict) -> "EpisodeRecord":
        """An episode as Minari's storage reader gives it (`get_episodes`), to write again."""
        record = cls(seed, episode["observations"][0], {k: v[0] for k, v in episode["infos"].items()})
        record.observations = list(episode["observations"])
        record.infos = {k: list(v) for k, v in episode["infos"].items()}
        record.actions, record.rewards = list(episode["actions"]), list(episode["rewards"])
        record.terminations, record.truncations = list(episode["terminations"]), list(episode["truncations"])
        return record

    def __len__(self) -> int:
        return len(self.actions)

    @property
    def ended(self) -> bool:
        """Ended by the env itself (terminated or truncated at its last step)."""
        return bool(self.actions) and bool(self.terminations[-1] or self.truncations[-1])

    def arrays(self, cut: bool) -> dict[str, Any]:
        """The episode's arrays in Minari's dtypes; `cut` marks an episode stopped from outside
        (the end of collection, a reset): truncated at its last step, which the env did not end."""
        truncations = np.array(self.truncations, np.bool_)
        if cut:
            truncations[-1] = True
        return {"observations": np.stack(self.observations), "actions": np.array(self.actions, np.int64),
                "rewards": np.array(self.rewards, np.float32),
                "terminations": np.array(self.terminations, np.bool_), "truncations": truncations,
                "infos": {name: np.array(values) for name, values in self.infos.items()}}


class DatasetWriter:
    """Creates a Minari dataset (metadata through Minari itself), then appends finished episodes
    compactly in groups of at least `flush_steps` steps.

    Args:
        dataset_id: Minari's `namespace/name-vN` (checked by `check_dataset_id`).
        env_spec: the spec `recover_environment()` builds (`octax_gym.datasets.recovery_spec`).
        observation_space, action_space: the dataset's spaces.
        flush_steps: finished episodes are written once they hold this many steps.
        metadata: Minari's metadata arguments (algorithm_name, author, description, ...); None
            values are left out.
        extra_metadata: more keys for metadata.json (the policy card of a suite dataset, say).
        compress: False writes the observations without filters (faster to read, ~70x larger).
    """

    def __init__(self, dataset_id: str, env_spec, observation_space, action_space, flush_steps: int,
                 metadata: dict[str, Any], extra_metadata: Optional[dict[str, Any]] = None, compress: bool = True):
        minari = import_minari()
        given = {name: value for name, value in metadata.items() if value is not None}
        with warnings.catch_warnings():  # Minari's "author is None, recommended" notes: optional here
            warnings.filterwarnings("ignore", message=r".*is set to None", category=UserWarning)
            dataset = minari.create_dataset_from_buffers(
                dataset_id, [], env=env_spec, observation_space=observation_space, action_space=action_space,
                requirements=["octax-gym"], data_format="hdf5", jpeg_encoding=False, **given)
        self._storage = dataset.storage
        self.path = Path(dataset.storage.data_path)  # <dataset>/data
        self._filters = OBSERVATION_FILTERS if compress else {}
        self._storage.update_metadata({"observation_filters": FILTERS_NAME if compress else "none",
                                       **(extra_metadata or {})})
        self._flush_steps = flush_steps
        self._pending: list[tuple[int, dict]] = []  # (seed, arrays) not yet written
        self._pending_steps = 0
        self.episodes = self.steps = 0

    def add(self, episode: EpisodeRecord, cut: bool) -> None:
        self._pending.append((episode.seed, episode.arrays(cut)))
        self._pending_steps += len(episode)
        if self._pending_steps >= self._flush_steps:
            self.flush()

    def close(self):
        """Writes what is left; returns the `minari.MinariDataset`."""
        self.flush()
        import minari

        return minari.MinariDataset(self.path)

    def flush(self) -> None:
        """Writes the pending episodes, then the metadata's totals (so the dataset on disk is whole
        after every flush)."""
        if not self._pending:
            return
        import h5py

        with h5py.File(self.path / "main_data.hdf5", "a", libver=LIBVER, track_order=True) as file:
            for seed, arrays in self._pending:
                self._write_episode(file, self.episodes, seed, arrays)
                self.episodes += 1
                self.steps += len(arrays["actions"])
        self._pending, self._pending_steps = [], 0
        self._storage.update_metadata({"total_episodes": self.episodes, "total_steps": self.steps,
                                       "dataset_size": self._storage.get_size()})

    def _write_episode(self, file, episode_id: int, seed: int, arrays: dict[str, Any]) -> None:
        group = file.create_group(f"episode_{episode_id}")
        group.attrs["id"] = episode_id
        group.attrs["seed"] = seed
        group.attrs["total_steps"] = len(arrays["actions"])
        observations = arrays["observations"]
        chunks = (min(CHUNK_STEPS, len(observations)), *observations.shape[1:]) if self._filters else None
        group.create_dataset("observations", data=observations, chunks=chunks, **self._filters)
        for name in ("actions", "rewards", "terminations", "truncations"):
            group.create_dataset(name, data=arrays[name])
        infos = group.create_group("infos")
        for name, values in arrays["infos"].items():
            infos.create_dataset(name, data=values)


def import_minari():
    try:
        import h5py  # noqa: F401  (Minari's HDF5 storage; its own error would name minari[hdf5])
        import minari
        import minari.data_collector
        import minari.storage
    except ImportError as exc:
        raise ImportError(f"octax_gym.datasets needs Minari with HDF5 (the datasets extra): "
                          f"{INSTALL_HINT} ({exc})") from exc
    return minari


def check_dataset_id(dataset_id) -> None:
    from minari.dataset.minari_dataset import DATASET_ID_RE

    match = DATASET_ID_RE.fullmatch(dataset_id) if isinstance(dataset_id, str) else None
    if match is None or match.group("version") is None:
        raise ValueError(f"dataset_id must look like 'namespace/name-v0' (Minari's format: an optional "
                         f"namespace/, a name of letters, digits, '-' and '_', and a version -vN), "
                         f"got {dataset_id!r}")
