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
the observations are stored. A random-play dataset comes out dozens of times smaller than
Minari's writer makes it (benchmarks/README.md, datasets.py, has the sizes).

A collection can be killed at any instant (a cluster's preemption, SIGKILL, Ctrl-C) and leave a
readable dataset of the episodes it had written, or no dataset, never a damaged one. Every file is
written under a temporary name and renamed into place (an atomic step on POSIX), never changed in
place:
- the dataset is created (Minari's metadata) in a hidden staging folder under the datasets root,
  then its folder is renamed to the dataset's path: before that there is no dataset;
- finished episodes are written in groups of at least `flush_steps` steps (memory holds one group),
  each group to a file of its own, `data/parts/part-NNNNN.hdf5`;
- then `main_data.hdf5` is replaced by a copy that adds an HDF5 external link `episode_<id>` to
  each new episode's group in its part (HDF5 resolves it beside the file, and h5py and Minari read
  through links as through groups), then `metadata.json` by a copy with the new totals;
- `close()` copies every episode into one self-contained `main_data.hdf5` (HDF5's object copy,
  compressed chunks as they are), renames it into place and deletes the parts.
A collection killed part way is a dataset of links into its parts, readable as it is;
`finish_dataset` turns it into the one-file form `close()` leaves.

A full disk ends the writer as a kill would, with an error instead: every HDF5 file is written
through `diskwrite.HDF5Writing` (libhdf5's own driver crashed the process on a failed write), the
temporary file is removed, and `DatasetWriteError` (an OSError) names the file and says what is
kept. `finish_dataset` checks a folder before it changes anything (`damage.check_dataset_files`).
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import shutil
import warnings
from pathlib import Path
from typing import Any, Optional

import numpy as np

from octax_gym.datasets.damage import DamagedDatasetError, check_dataset_files, reading_hdf5
from octax_gym.datasets.diskwrite import DatasetWriteError, HDF5Writing, is_out_of_space

INSTALL_HINT = 'pip install "octax-gym[datasets]"'

# h5py's create_dataset filter arguments for the observations. scaleoffset=0: the fewest bits each
# chunk's integers need, found per chunk. Deflate level 1, the fastest: collection writes while it
# runs, and a higher level buys a somewhat smaller file with a slower collection (measured:
# benchmarks/README.md, datasets.py).
OBSERVATION_FILTERS = {"scaleoffset": 0, "compression": "gzip", "compression_opts": 1}
FILTERS_NAME = "scaleoffset+gzip1"
CHUNK_STEPS = 64  # observations per HDF5 chunk (the unit compressed and read back together)
# HDF5's newest object formats: smaller per-dataset headers and chunk indexes than the 1.8-compatible
# default, which matters for short episodes (a random Brix episode is 33 steps). HDF5 >= 1.10 reads it.
LIBVER = "latest"
PARTS = "parts"  # data/parts/: a killed collection's episodes, linked from main_data.hdf5
MAIN_DATA, METADATA = "main_data.hdf5", "metadata.json"
STAGING = ".octax-incomplete"  # under the datasets root; hidden, so Minari's listing skips it


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
        compress: False writes the observations without filters: faster to read, but every
            zero and repeated pixel is stored (sizes: benchmarks/README.md, datasets.py).
    """

    def __init__(self, dataset_id: str, env_spec, observation_space, action_space, flush_steps: int,
                 metadata: dict[str, Any], extra_metadata: Optional[dict[str, Any]] = None, compress: bool = True):
        import_minari()
        from minari.storage import get_dataset_path

        given = {name: value for name, value in metadata.items() if value is not None}
        final = Path(get_dataset_path(dataset_id))
        if final.exists():  # Minari's own refusal, before any work
            raise ValueError(f"A Minari dataset with ID {dataset_id} already exists and it cannot be overridden. "
                             f"Please use a different dataset name or version.")
        extra = {"observation_filters": FILTERS_NAME if compress else "none", **(extra_metadata or {})}
        self.path = _create(dataset_id, final, dict(env=env_spec, observation_space=observation_space,
                                                    action_space=action_space, **given), extra) / "data"
        self._filters = OBSERVATION_FILTERS if compress else {}
        self._flush_steps = flush_steps
        self._pending: list[tuple[int, dict]] = []  # (seed, arrays) not yet written
        self._pending_steps = 0
        self._parts = 0
        self.episodes = self.steps = 0

    def add(self, episode: EpisodeRecord, cut: bool) -> None:
        self._pending.append((episode.seed, episode.arrays(cut)))
        self._pending_steps += len(episode)
        if self._pending_steps >= self._flush_steps:
            self.flush()

    def close(self):
        """Writes what is left, makes `main_data.hdf5` one self-contained file; returns the
        `minari.MinariDataset`.

        Raises:
            DatasetWriteError: a write failed (a full disk); the message says what is kept.
        """
        self.flush()
        try:
            finish_dataset(self.path.parent)
        except DatasetWriteError as exc:
            raise exc.with_outcome(_kept_outcome(self.path.parent)) from exc
        import minari

        return minari.MinariDataset(self.path)

    def flush(self) -> None:
        """Writes the pending episodes to a new part, links them from `main_data.hdf5`, then writes
        the metadata's totals; each file is renamed into place whole, so the dataset on disk is
        whole at every instant.

        Raises:
            DatasetWriteError: a write failed (a full disk): the dataset is as the last flush left
                it, and the message says so.
        """
        try:
            self._flush()
        except DatasetWriteError as exc:
            raise exc.with_outcome(_kept_outcome(self.path.parent)) from exc

    def _flush(self) -> None:
        if not self._pending:
            return
        import h5py

        part = Path(PARTS) / f"part-{self._parts:05d}.hdf5"
        try:
            (self.path / PARTS).mkdir(exist_ok=True)
        except OSError as exc:
            if is_out_of_space(exc):
                raise DatasetWriteError(exc.errno, self.path / PARTS) from exc
            raise
        first = self.episodes
        with _replacing(self.path / part) as tmp, HDF5Writing(tmp, "w") as out:
            for i, (seed, arrays) in enumerate(self._pending):
                self._write_episode(out.file, first + i, seed, arrays)
                out.check()  # a full disk stops the part here
        with _replacing(self.path / MAIN_DATA) as tmp:
            shutil.copyfile(self.path / MAIN_DATA, tmp)
            with HDF5Writing(tmp, "r+") as out:
                for i in range(first, first + len(self._pending)):
                    out.file[f"episode_{i}"] = h5py.ExternalLink(part.as_posix(), f"/episode_{i}")
        self._parts += 1
        self.episodes += len(self._pending)
        self.steps += sum(len(arrays["actions"]) for _, arrays in self._pending)
        self._pending, self._pending_steps = [], 0
        update_metadata(self.path, {"total_episodes": self.episodes, "total_steps": self.steps,
                                    "dataset_size": data_size(self.path)})

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


def finish_dataset(dataset) -> bool:
    """Makes a dataset written in parts (a collection killed part way, or one being closed) one
    self-contained `main_data.hdf5`: every linked episode copied in (HDF5's object copy moves the
    compressed chunks as they are), the file renamed into place, then the parts deleted. Safe to
    kill at any point and to run again. Returns False when there was nothing to do.

    Args:
        dataset: a dataset id ("octax/Brix-random-v0", under Minari's datasets root) or the
            dataset's folder (the one holding data/).

    Raises:
        FileNotFoundError: no such dataset.
        DamagedDatasetError: a file of the dataset is missing or unreadable (the message names
            it); nothing is changed.
        DatasetWriteError: a write failed (a full disk); the dataset is as it was.
    """
    import h5py

    data = dataset_folder(dataset) / "data"
    check_dataset_files(data)
    parts = data / PARTS
    if not parts.exists():
        return False
    with reading_hdf5(data / MAIN_DATA) as linked:
        names = list(linked.keys())
        links = {name: linked.get(name, getlink=True) for name in names}
    if any(isinstance(link, h5py.ExternalLink) for link in links.values()):
        try:
            _copy_into_one_file(data, names, links)
        except DatasetWriteError as exc:
            raise exc.with_outcome(f"the dataset at {data.parent} is unchanged and loads as it is, its episodes "
                                   f"read through {PARTS}/; free space and run `octax-gym dataset finish "
                                   f"{data.parent}` again (it needs room for a copy of the episodes)") from exc
    shutil.rmtree(parts)
    update_metadata(data, {"dataset_size": data_size(data)})
    return True


def _copy_into_one_file(data: Path, names: list[str], links: dict[str, Any]) -> None:
    """Every linked episode copied into a new main_data.hdf5, renamed into place."""
    import h5py

    with _replacing(data / MAIN_DATA) as tmp, HDF5Writing(tmp, "w") as out, contextlib.ExitStack() as stack:
        sources: dict[str, Any] = {}
        for name in names:
            link = links[name]
            if not isinstance(link, h5py.ExternalLink):
                raise DamagedDatasetError(data / MAIN_DATA, f"holds {name} as well as links into {PARTS}/ (a "
                                                            "dataset writes one or the other)")
            if link.filename not in sources:
                sources[link.filename] = stack.enter_context(reading_hdf5(data / link.filename))
            try:
                sources[link.filename].copy(link.path, out.file, name=name)
            except (OSError, KeyError, RuntimeError) as exc:
                out.check()  # a full disk, not the part, when the write failed
                raise DamagedDatasetError(data / link.filename, f"cannot give {link.path} ({exc})") from exc
            out.check()


def kept_episodes(folder) -> tuple[int, int]:
    """(episodes, steps) that the dataset at `folder` holds by its metadata.json; (0, 0) where
    there is none or it cannot be read."""
    try:
        metadata = json.loads((Path(folder) / "data" / METADATA).read_text())
        return int(metadata["total_episodes"]), int(metadata["total_steps"])
    except (OSError, ValueError, KeyError, TypeError):
        return 0, 0


def _kept_outcome(folder: Path) -> str:
    """What a writer stopped by a failed write leaves, said for its error."""
    episodes, steps = kept_episodes(folder)
    return (f"the {episodes} episodes ({steps} steps) written before are kept at {folder} and load as they are; "
            f"free space, then run `octax-gym dataset finish {folder}` to make them one file (or delete the folder)")


def dataset_folder(dataset) -> Path:
    """The folder (holding data/) of a dataset id under Minari's datasets root, or of a folder.

    Raises:
        FileNotFoundError: neither names a dataset.
    """
    folder = Path(dataset)
    if not (folder / "data").is_dir():
        from minari.storage import get_dataset_path

        folder = Path(get_dataset_path(str(dataset)))
        if not (folder / "data").is_dir():
            raise FileNotFoundError(f"no dataset {str(dataset)!r}: neither a dataset folder (with data/) nor a "
                                    f"dataset id under {get_dataset_path()}")
    return folder


def update_metadata(data_path: Path, changes: dict[str, Any]) -> None:
    """metadata.json with `changes`, written whole under a temporary name and renamed into place
    (Minari's own update rewrites the file in place, which a kill can leave half-written)."""
    path = Path(data_path) / METADATA
    metadata = json.loads(path.read_text())
    metadata.update(changes)
    with _replacing(path) as tmp:
        tmp.write_text(json.dumps(metadata, default=_json_value))


def _json_value(value):
    """What metadata.json holds for a set (Minari's author and author_email): a list, as Minari writes it."""
    if isinstance(value, set):
        return sorted(value)
    raise TypeError(f"metadata value of type {type(value).__name__} is not JSON serializable")


def data_size(data_path: Path) -> float:
    """The dataset's size in MB, as Minari counts it (every file under data/)."""
    return sum(f.stat().st_size for f in Path(data_path).glob("**/*") if f.is_file()) / 1e6


class _replacing:
    """`with _replacing(path) as tmp:` write `tmp`; on success it is synced and renamed to `path`
    (and the folder synced), on an exception removed. A kill at any point leaves `path` as it was
    or as the whole new file. A full disk while writing or syncing `tmp` raises
    `DatasetWriteError` naming `path`, `tmp` removed."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")

    def __enter__(self) -> Path:
        return self.tmp

    def __exit__(self, kind, value, traceback):
        if kind is None:
            try:
                with open(self.tmp, "rb") as f:
                    os.fsync(f.fileno())  # where a filesystem reports a full disk late (NFS), it is here
                os.replace(self.tmp, self.path)
            except OSError as exc:
                self.tmp.unlink(missing_ok=True)
                if is_out_of_space(exc):
                    raise DatasetWriteError(exc.errno, self.path) from exc
                raise
            _sync_dir(self.path.parent)
            return False
        self.tmp.unlink(missing_ok=True)
        if is_out_of_space(value) and not isinstance(value, DatasetWriteError):
            raise DatasetWriteError(value.errno, self.path) from value
        if isinstance(value, DatasetWriteError) and value.filename == str(self.tmp):
            raise DatasetWriteError(value.errno, self.path) from value  # the file's own name, not the temporary one
        return False


def _sync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # some filesystems cannot open a folder; the rename is atomic regardless
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _create(dataset_id: str, final: Path, arguments: dict[str, Any], extra: dict[str, Any]) -> Path:
    """The dataset created by Minari (its metadata.json, an empty main_data.hdf5) in a hidden
    staging folder of the datasets root, completed, then renamed to `final`: there is a dataset at
    `final` only once it is whole. Returns `final`."""
    import minari
    from minari.namespace import create_namespace, list_local_namespaces
    from minari.storage import get_dataset_path
    from minari.utils import parse_dataset_id

    root = Path(get_dataset_path())
    staging = root / STAGING / f"{os.getpid()}-{secrets.token_hex(4)}"
    before = os.environ.get("MINARI_DATASETS_PATH")
    os.environ["MINARI_DATASETS_PATH"] = str(staging)  # Minari places a new dataset under this root
    try:
        with warnings.catch_warnings():  # Minari's "author is None, recommended" notes: optional here
            warnings.filterwarnings("ignore", message=r".*is set to None", category=UserWarning)
            dataset = minari.create_dataset_from_buffers(dataset_id, [], requirements=["octax-gym"],
                                                         data_format="hdf5", jpeg_encoding=False, **arguments)
        built = Path(dataset.storage.data_path)
    finally:
        if before is None:
            os.environ.pop("MINARI_DATASETS_PATH", None)
        else:
            os.environ["MINARI_DATASETS_PATH"] = before
    try:
        update_metadata(built, extra)
        if not (built / MAIN_DATA).exists():  # Minari writes no file for an empty buffer list
            with _replacing(built / MAIN_DATA) as tmp, HDF5Writing(tmp, "w"):
                pass
        namespace = parse_dataset_id(dataset_id)[0]
        if namespace and namespace not in list_local_namespaces():
            try:
                create_namespace(namespace)
            except ValueError:  # another process (a shard of the same run) made it first
                pass
        final.parent.mkdir(parents=True, exist_ok=True)
        try:
            os.rename(built.parent, final)
        except OSError as exc:  # another writer took the id in the meantime
            if final.exists():
                raise ValueError(f"A Minari dataset with ID {dataset_id} already exists and it cannot be "
                                 f"overridden. Please use a different dataset name or version.") from exc
            raise
        _sync_dir(final.parent)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return final


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
