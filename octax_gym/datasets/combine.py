"""Collection in shards, one per process or machine, and the step that makes them one dataset.

    octax-gym dataset collect Brix --dataset-id octax/Brix-random-v0 --steps 1000000 --shard 0 --num-shards 4
    ...                                                                          (shards 1, 2, 3 elsewhere)
    octax-gym dataset combine octax/Brix-random-shard0-v0 ... octax/Brix-random-shard3-v0 --dataset-id octax/Brix-random-v0

Shard r of P collects its part of the steps with seeds of its own: the seeds a collection of S
steps in K lanes can use lie in seed .. seed + K + S - 1, so shard r starts at
seed + r * (K + S_0), S_0 the first shard's steps, and no two shards share an episode seed.
The shards need no coordination: each is an ordinary collection (`collect_dataset`) run anywhere.
`combine_datasets` then writes their episodes, in shard order, into one compact dataset with
their own seeds, after checking the shards were collected in the same env: every episode still
replays exactly from its seed in `recover_environment()`.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path
from typing import Optional, Sequence

from octax_core.validate import check_int


def shard_plan(num_steps: int, num_envs: int, seed: int, shard: int, num_shards: int) -> tuple[int, int]:
    """(steps, first seed) of shard `shard` of `num_shards` of a collection of `num_steps` steps in
    `num_envs` lanes from `seed`: the steps split as evenly as they go (the first shards take the
    remainder), the seed ranges disjoint."""
    check_int("num_shards", num_shards)
    check_int("shard", shard, minimum=0, maximum=num_shards - 1)
    if num_steps < num_shards:
        raise ValueError(f"num_steps={num_steps} is fewer than num_shards={num_shards}: every shard needs a step")
    base, extra = divmod(num_steps, num_shards)
    steps = base + (shard < extra)
    stride = num_envs + base + (extra > 0)  # the largest shard's seed range
    return steps, seed + shard * stride


def shard_dataset_id(dataset_id: str, shard: int) -> str:
    """`namespace/name-vN` -> `namespace/name-shard<r>-vN`."""
    match = re.fullmatch(r"(?P<stem>.+)-v(?P<version>\d+)", dataset_id)
    if match is None:
        raise ValueError(f"dataset_id must end in a version -vN, got {dataset_id!r}")
    return f"{match['stem']}-shard{shard}-v{match['version']}"


def combine_datasets(shard_ids: Sequence[str], dataset_id: str, *, overwrite: bool = False,
                     description: Optional[str] = None):
    """Writes the episodes of the shards, in order, into the dataset `dataset_id`; returns it.

    Raises:
        ValueError: fewer than one shard, shards of different envs or spaces, a seed in two
            shards, or an existing `dataset_id` without `overwrite`.
        DatasetWriteError: an OSError: a write failed (a full disk); the combined dataset is
            removed, the shards are unchanged.
    """
    from octax_gym.datasets.diskwrite import DatasetWriteError
    from octax_gym.datasets.storage import DatasetWriter, EpisodeRecord, check_dataset_id, import_minari

    minari = import_minari()
    check_dataset_id(dataset_id)
    if not shard_ids:
        raise ValueError("combine_datasets needs at least one shard")
    shards = [minari.load_dataset(ident) for ident in shard_ids]
    first = shards[0]
    for ident, shard in zip(shard_ids[1:], shards[1:]):
        if (shard.spec.env_spec != first.spec.env_spec or shard.observation_space != first.observation_space
                or shard.action_space != first.action_space):
            raise ValueError(f"{ident!r} was collected in another env or with other spaces than {shard_ids[0]!r}: "
                             f"{shard.spec.env_spec} against {first.spec.env_spec}")
    seeds = [int(m["seed"]) for shard in shards for m in shard.storage.get_episode_metadata(shard.episode_indices)]
    if len(set(seeds)) != len(seeds):
        raise ValueError("two shards hold episodes of the same seed: collect shard r with its own seeds "
                         "(`shard_plan`, or --shard R --num-shards P)")
    path = minari.storage.get_dataset_path(dataset_id)
    if path.exists():
        if not overwrite:
            raise ValueError(f"dataset {dataset_id!r} already exists at {path}; pass overwrite=True to replace it")
        shutil.rmtree(path)
    raw = json.loads((Path(first.storage.data_path) / "metadata.json").read_text())
    metadata = {"algorithm_name": raw.get("algorithm_name"), "author": _one(raw.get("author")),
                "author_email": _one(raw.get("author_email")), "code_permalink": raw.get("code_permalink"),
                "description": description or (f"{len(shards)} shards combined: {', '.join(shard_ids)}. "
                                               f"{raw.get('description', '')}")}
    try:
        writer = DatasetWriter(dataset_id, first.spec.env_spec, first.observation_space, first.action_space,
                               flush_steps=20_000, metadata=metadata,
                               extra_metadata={"shards": list(shard_ids),
                                               **{k: raw[k] for k in ("policy", "suite") if k in raw}})
        for shard in shards:
            metas = shard.storage.get_episode_metadata(shard.episode_indices)
            for meta, episode in zip(metas, shard.storage.get_episodes(shard.episode_indices)):
                writer.add(EpisodeRecord.from_stored(int(meta["seed"]), episode), cut=False)
        return writer.close()
    except DatasetWriteError as exc:
        shutil.rmtree(path, ignore_errors=True)
        raise exc.with_outcome(f"{dataset_id!r} is removed; the shards are unchanged") from exc
    except BaseException:
        shutil.rmtree(path, ignore_errors=True)
        raise


def _one(value):
    """Minari stores author fields as lists in metadata.json; its writer takes a string."""
    if isinstance(value, list):
        return ", ".join(map(str, value)) or None
    return value
