"""`octax-gym play --record ID`: the human's episodes as a Minari dataset, in the format of
`octax_gym.datasets.collect_dataset` and through its writer: exact uint8 observations, actions,
rewards, flags, infos (score, lives, episode_step) and the seed that replays each episode in
`dataset.recover_environment()` (`octax_gym.datasets.episode_seed`). The metadata names the
recorder: `algorithm_name` "human", `author` the recorder's name.

Only episodes a human played from start to end are kept (one where an agent or a random player
took a seat is left out); one stopped by a reset is stored cut (truncated at its last step), as
`collect_dataset` stores the episodes still running when it stops. Each episode is written when it
ends, so a crash loses at most the one in play.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any, Optional

import numpy as np

from gymnasium import spaces

from octax_gym import datasets
from octax_gym.datasets import storage
from octax_gym.envs.game_names import resolve_env_id


class Recorder:
    def __init__(self, game: str, dataset_id: str, *, observation_space, num_actions: int,
                 recorder: str = "human", overwrite: bool = False, env_options: Optional[dict] = None,
                 description: Optional[str] = None):
        minari = storage.import_minari()
        storage.check_dataset_id(dataset_id)
        gym_id = resolve_env_id(game)
        path = minari.storage.get_dataset_path(dataset_id)
        if path.exists() and not overwrite:
            raise ValueError(f"dataset {dataset_id!r} already exists at {path}; pass --overwrite to replace it, "
                             "or pick another name or version")
        if path.exists():
            shutil.rmtree(path)
        self.dataset_id, self.path = dataset_id, Path(path)
        metadata = {"algorithm_name": "human", "author": recorder,
                    "description": description or (f"{gym_id}, played by a human ({recorder}) in the browser with "
                                                    "`octax-gym play --record`; episode seeds in the episode "
                                                    "metadata replay each episode")}
        self._writer = storage.DatasetWriter(dataset_id, datasets.recovery_spec(gym_id, env_options or {}),
                                             observation_space, spaces.Discrete(num_actions), 1, metadata)
        self._episode: Optional[storage.EpisodeRecord] = None
        self.dataset = None

    @property
    def episodes(self) -> int:
        return self._writer.episodes

    @property
    def steps(self) -> int:
        return self._writer.steps

    def start(self, seed: int, obs: np.ndarray, info: dict[str, Any]) -> None:
        self._episode = storage.EpisodeRecord(seed, np.asarray(obs), info)

    def add(self, action: int, obs: np.ndarray, reward: float, terminated: bool, truncated: bool,
            info: dict[str, Any]) -> None:
        if self._episode is not None:
            self._episode.add(int(action), np.asarray(obs), reward, terminated, truncated, info)

    def finish(self, cut: bool, keep: bool = True) -> None:
        """Writes the episode in play if a human played it and it has a step; `cut`: it did not
        end by itself (a reset, or the server stopping)."""
        episode, self._episode = self._episode, None
        if episode is None or not len(episode) or not keep:
            return
        self._writer.add(episode, cut=cut and not episode.ended)

    def close(self):
        """Writes what is left; returns the `minari.MinariDataset`."""
        if self.dataset is None:
            self.dataset = self._writer.close()
        return self.dataset
