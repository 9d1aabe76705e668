"""A damaged dataset folder named as such: which file, what is wrong with it, what to do.

A dataset's folder can be damaged from outside: a copy cut short, a disk error, a file edited or
deleted by hand. Read as they are, its files fail deep inside h5py ("Unable to synchronously open
file (file signature not found)", naming no file), json, or Minari's loader, whose checks of
metadata.json are bare `assert`s (an AssertionError with no message). `check_dataset_files`
reads what `dataset finish` and Minari's loader rely on before either does, and raises
`DamagedDatasetError`, a ValueError, naming the file: metadata.json (a JSON object with Minari's
keys), main_data.hdf5, and every part the first `total_episodes` episodes link into. It opens the
files and follows the links; it does not read the episodes' arrays.
"""

from __future__ import annotations

import contextlib
import json
from pathlib import Path
from typing import Any, Iterator

# metadata.json's keys that Minari's loader reads without a default, and their JSON types
REQUIRED_METADATA = {"dataset_id": str, "minari_version": str, "data_format": str, "observation_space": str,
                     "action_space": str, "total_episodes": int, "total_steps": int}
ADVICE = ("Nothing was changed. Restore the file from a copy, or collect the dataset again "
          "(`octax-gym dataset collect ... --overwrite`).")


class DamagedDatasetError(ValueError):
    """A file of a dataset is missing or cannot be read; the message names it and what to do."""

    def __init__(self, path, problem: str):
        path = Path(path)
        self.path, self.problem = path, problem
        folder = path.parent.parent if path.parent.name == "parts" else path.parent
        super().__init__(f"dataset {folder.parent} is damaged: {path.relative_to(folder.parent)} {problem}. {ADVICE}")


def read_metadata(data: Path) -> dict[str, Any]:
    """metadata.json of the dataset whose data/ folder is `data`, checked to hold what Minari reads."""
    from octax_gym.datasets.storage import METADATA

    path = Path(data) / METADATA
    if not path.is_file():
        raise DamagedDatasetError(path, "is missing (it holds the dataset's spaces, env spec and totals)")
    try:
        metadata = json.loads(path.read_bytes())
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DamagedDatasetError(path, f"is not valid JSON ({exc})") from exc
    if not isinstance(metadata, dict):
        raise DamagedDatasetError(path, f"holds a JSON {type(metadata).__name__}, not the object of Minari's keys")
    for key, kind in REQUIRED_METADATA.items():
        value = metadata.get(key)
        if not isinstance(value, kind) or isinstance(value, bool) or (kind is int and value < 0):
            wanted = "a count (an integer >= 0)" if kind is int else "a string"
            raise DamagedDatasetError(path, f"has {key} = {json.dumps(value)[:80]}, where {wanted} belongs")
    if metadata["data_format"] != "hdf5":
        raise DamagedDatasetError(path, f"has data_format = {metadata['data_format']!r}: octax-gym writes and "
                                        "finishes 'hdf5' datasets only")
    return metadata


@contextlib.contextmanager
def reading_hdf5(path: Path) -> Iterator[Any]:
    """The HDF5 file at `path` opened read-only; a missing or unreadable one is a `DamagedDatasetError`."""
    import h5py

    path = Path(path)
    if not path.is_file():
        raise DamagedDatasetError(path, "is missing")
    try:
        file = h5py.File(path, "r")
    except OSError as exc:
        raise DamagedDatasetError(path, f"is not a readable HDF5 file, cut short or overwritten ({exc})") from exc
    with file:
        yield file


def check_dataset_files(data: Path) -> dict[str, Any]:
    """Checks the dataset whose data/ folder is `data`: its metadata.json, its main_data.hdf5, and
    that each of the first `total_episodes` episodes is there, in main_data.hdf5 or through its link
    into a part. Returns the metadata."""
    import h5py

    from octax_gym.datasets.storage import MAIN_DATA, METADATA

    data = Path(data)
    metadata = read_metadata(data)
    total = metadata["total_episodes"]
    with reading_hdf5(data / MAIN_DATA) as main, contextlib.ExitStack() as stack:
        parts: dict[str, Any] = {}
        for i in range(total):
            name = f"episode_{i}"
            link = main.get(name, getlink=True)
            if link is None:
                raise DamagedDatasetError(data / MAIN_DATA, f"has no {name}, though data/{METADATA} counts "
                                                            f"{total} episodes")
            if isinstance(link, h5py.ExternalLink):
                if link.filename not in parts:
                    parts[link.filename] = stack.enter_context(reading_hdf5(data / link.filename))
                where = data / link.filename
                group = _get(parts[link.filename], link.path, where)
            else:
                where, group = data / MAIN_DATA, _get(main, name, data / MAIN_DATA)
            if not isinstance(group, h5py.Group) or "actions" not in group or "observations" not in group:
                raise DamagedDatasetError(where, f"has no episode group {name} with its observations and actions")
    return metadata


def _get(file, name: str, path: Path):
    try:
        return file.get(name)
    except (OSError, KeyError, RuntimeError) as exc:
        raise DamagedDatasetError(path, f"cannot give {name} ({exc})") from exc


def load_checked(data: Path):
    """`minari.MinariDataset` of the data/ folder `data`, after `check_dataset_files`; what Minari's
    loader still refuses (its bare asserts, say) is a `DamagedDatasetError` on metadata.json."""
    import minari

    from octax_gym.datasets.storage import METADATA

    check_dataset_files(data)
    try:
        return minari.MinariDataset(data)
    except (AssertionError, KeyError, TypeError, AttributeError, json.JSONDecodeError) as exc:
        raise DamagedDatasetError(Path(data) / METADATA, f"does not load in Minari ({type(exc).__name__}: "
                                                         f"{exc or 'a failed check'})") from exc
