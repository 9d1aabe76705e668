"""A collection killed at any point leaves a readable dataset of the episodes it had written, or
none, never a damaged one (octax_gym/datasets/storage.py): real processes SIGKILLed at chosen
points inside the writer (tests/dataset_kill_worker.py), then a real collection killed at a moment
chosen by the clock, its episodes replayed from their seeds. Every subprocess runs under a timeout.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

minari = pytest.importorskip("minari")
h5py = pytest.importorskip("h5py")

from octax_gym.datasets import storage  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests"))
import dataset_kill_worker as worker  # noqa: E402

TIMEOUT_S = 120
PER_FLUSH = worker.EPISODES_PER_FLUSH


def run_worker(point: str, root: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "MINARI_DATASETS_PATH": str(root),
           "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run([sys.executable, str(REPO / "tests" / "dataset_kill_worker.py"), point], env=env,
                          capture_output=True, text=True, timeout=TIMEOUT_S)


def check_dataset(root: Path, episodes: int) -> None:
    """The dataset at root loads through Minari with exactly the first `episodes` episodes, each
    equal to what the worker wrote."""
    os.environ["MINARI_DATASETS_PATH"] = str(root)
    dataset = minari.load_dataset(worker.DATASET_ID)
    assert dataset.total_episodes == episodes
    assert dataset.total_steps == sum(worker.E_STEPS[:episodes])
    for e, stored in enumerate(dataset.iterate_episodes()):
        arrays = worker.episode(e).arrays(cut=False)
        for name in ("observations", "actions", "rewards", "terminations", "truncations"):
            assert np.array_equal(getattr(stored, name), arrays[name]), (e, name)
        assert np.array_equal(stored.infos["score"], arrays["infos"]["score"])
    assert worker.DATASET_ID in minari.list_local_datasets()


def is_one_file(root: Path) -> bool:
    """main_data.hdf5 holds every episode itself, no link into the parts."""
    with h5py.File(root / worker.DATASET_ID / "data" / storage.MAIN_DATA, "r") as file:
        links = [file.get(name, getlink=True) for name in file]
    return bool(links) and not any(isinstance(link, h5py.ExternalLink) for link in links)


@pytest.fixture(autouse=True)
def restore_minari_path(monkeypatch):
    monkeypatch.setenv("MINARI_DATASETS_PATH", os.environ.get("MINARI_DATASETS_PATH", ""))


# kill point: (episodes readable after the kill, one self-contained file already)
KILLS = {
    "none": (3 * PER_FLUSH, True),
    "part": (PER_FLUSH, False),           # the second part was being written: the first flush's episodes
    "index": (PER_FLUSH, False),          # its links were being added: the old main_data.hdf5 stands
    "metadata": (PER_FLUSH, False),       # the new links are in, the totals still the old ones
    "finish": (3 * PER_FLUSH, False),     # close() was copying: every episode, through the links
    "cleanup": (3 * PER_FLUSH, True),     # the one file is in place, the parts not yet deleted
}


@pytest.mark.parametrize("point", list(KILLS))
def test_a_writer_killed_anywhere_leaves_a_whole_dataset(tmp_path, point):
    done = run_worker(point, tmp_path)
    if point == "none":
        assert done.returncode == 0 and "closed" in done.stdout, done.stderr[-2000:]
    else:
        assert done.returncode == -signal.SIGKILL, (done.returncode, done.stderr[-2000:])
    episodes, one_file = KILLS[point]
    check_dataset(tmp_path, episodes)
    assert is_one_file(tmp_path) == one_file
    parts = tmp_path / worker.DATASET_ID / "data" / storage.PARTS
    assert parts.exists() == (point != "none")
    # finish_dataset makes a killed collection the one-file dataset close() leaves, with the same episodes
    assert storage.finish_dataset(tmp_path / worker.DATASET_ID) == (point != "none")
    check_dataset(tmp_path, episodes)
    assert is_one_file(tmp_path) and not parts.exists()
    metadata = json.loads((tmp_path / worker.DATASET_ID / "data" / storage.METADATA).read_text())
    assert metadata["observation_filters"] == storage.FILTERS_NAME and metadata["algorithm_name"] == "kill test"
    if point == "none":  # a closed writer leaves no temporary file
        assert not list((tmp_path / worker.DATASET_ID).rglob("*.tmp"))


def test_a_writer_killed_while_creating_leaves_no_dataset(tmp_path):
    done = run_worker("create", tmp_path)
    assert done.returncode == -signal.SIGKILL, done.stderr[-2000:]
    assert not (tmp_path / worker.DATASET_ID).exists()
    os.environ["MINARI_DATASETS_PATH"] = str(tmp_path)
    assert worker.DATASET_ID not in minari.list_local_datasets()  # the staging folder is hidden
    assert (tmp_path / storage.STAGING).exists()
    # the id is free: a new collection of it runs to the end
    assert run_worker("none", tmp_path).returncode == 0
    check_dataset(tmp_path, 3 * PER_FLUSH)


COLLECT = """
import sys
from octax_gym.datasets import collect_dataset
collect_dataset("Brix", "octax/Brix-killed-v0", 10**7, num_envs=4, seed=7, progress=False, max_episode_steps=40,
                flush_steps=64)
"""


@pytest.mark.slow  # a JAX collection in a subprocess and a replay of its episodes: 20-40 s on 2 cores
def test_a_collection_killed_by_the_clock_leaves_episodes_that_replay(tmp_path):
    """A real collection, SIGKILLed at a moment the clock picks once its third flush is on disk:
    wherever it was (stepping, writing a part, linking, the metadata), what is left loads, and every
    episode replays exactly from its stored seed."""
    import gymnasium as gym

    import octax_gym
    from octax_gym.datasets import episode_seed

    env = {**os.environ, "MINARI_DATASETS_PATH": str(tmp_path),
           "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    process = subprocess.Popen([sys.executable, "-c", COLLECT], env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    metadata = tmp_path / "octax" / "Brix-killed-v0" / "data" / storage.METADATA
    deadline = time.monotonic() + TIMEOUT_S
    try:
        while time.monotonic() < deadline and process.poll() is None:
            if metadata.exists() and json.loads(metadata.read_text()).get("total_steps", 0) >= 3 * 64:
                break
            time.sleep(0.05)
        assert process.poll() is None, process.communicate()[0][-3000:]
        assert time.monotonic() < deadline, "the collection wrote no third flush in time"
        time.sleep(float(np.random.default_rng().uniform(0, 0.3)))  # anywhere in what follows
    finally:
        process.send_signal(signal.SIGKILL)
        process.communicate(timeout=TIMEOUT_S)
    os.environ["MINARI_DATASETS_PATH"] = str(tmp_path)
    dataset = minari.load_dataset("octax/Brix-killed-v0")
    assert dataset.total_episodes >= 3 and dataset.total_steps >= 3 * 64
    gym.register_envs(octax_gym)
    replay = dataset.recover_environment()
    for episode in dataset.iterate_episodes():
        obs, _ = replay.reset(seed=episode_seed(dataset, episode.id))
        frames = [obs]
        for action in episode.actions:
            frames.append(replay.step(int(action))[0])
        assert np.array_equal(np.stack(frames), episode.observations), episode.id
    total = dataset.total_steps
    storage.finish_dataset(tmp_path / "octax" / "Brix-killed-v0")
    assert minari.load_dataset("octax/Brix-killed-v0").total_steps == total


def test_the_cli_finishes_a_killed_collection_and_names_an_unknown_one(tmp_path, capsys):
    from octax_gym import cli

    assert run_worker("index", tmp_path).returncode == -signal.SIGKILL
    assert not is_one_file(tmp_path)
    assert cli.main(["dataset", "finish", worker.DATASET_ID, "--data-path", str(tmp_path)]) == 0
    assert capsys.readouterr().out.strip() == f"{worker.DATASET_ID}: made one file; {PER_FLUSH} episodes, " \
                                             f"{sum(worker.E_STEPS[:PER_FLUSH])} steps"
    assert is_one_file(tmp_path)
    folder = str(tmp_path / worker.DATASET_ID)
    assert cli.main(["dataset", "finish", folder]) == 0  # by its folder; nothing left to do
    assert "already one file" in capsys.readouterr().out
    check_dataset(tmp_path, PER_FLUSH)
    assert cli.main(["dataset", "finish", "octax/Nothing-v0", "--data-path", str(tmp_path)]) == 1
    assert "no dataset 'octax/Nothing-v0'" in capsys.readouterr().err
