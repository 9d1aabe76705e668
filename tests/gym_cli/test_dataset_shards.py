"""Collection in shards (octax_gym/datasets/combine.py): two real processes collect their shards of
a Brix dataset at the same time (`octax-gym dataset collect --shard R --num-shards 2`), `octax-gym
dataset combine` makes them one dataset, and every episode of it replays exactly from its seed in
the recovered env. Each process runs under a timeout."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

minari = pytest.importorskip("minari")

from octax_gym import cli  # noqa: E402
from octax_gym.datasets import episode_seed  # noqa: E402
from octax_gym.datasets.combine import combine_datasets, shard_plan  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
STEPS, ENVS = 91, 3


def test_shard_plans_split_the_steps_and_keep_seeds_apart():
    plans = [shard_plan(10, 4, 100, r, 3) for r in range(3)]
    assert [steps for steps, _ in plans] == [4, 3, 3]
    assert [seed for _, seed in plans] == [100, 108, 116]  # each shard's seeds: at most 4 lanes + 4 steps
    with pytest.raises(ValueError, match="shard"):
        shard_plan(10, 4, 0, 3, 3)
    with pytest.raises(ValueError, match="fewer than num_shards"):
        shard_plan(2, 4, 0, 0, 3)


@pytest.mark.slow  # two collecting processes and a replay (~30 s); CI's test-slow runs it
def test_two_processes_collect_shards_that_combine_into_a_dataset_that_replays(tmp_path, monkeypatch, capsys):
    data = tmp_path / "minari"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    processes = [subprocess.Popen([sys.executable, "-m", "octax_gym", "dataset", "collect", "Brix",
                                   "--dataset-id", "octax/Brix-sharded-v0", "--steps", str(STEPS), "--envs", str(ENVS),
                                   "--seed", "7", "--max-episode-steps", "30", "--shard", str(rank), "--num-shards", "2",
                                   "--data-path", str(data), "--no-progress"], cwd=REPO, env=env,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) for rank in range(2)]
    for process in processes:
        try:
            out, _ = process.communicate(timeout=300)
        except subprocess.TimeoutExpired:
            process.kill()
            pytest.fail("a shard's collection did not finish in 300 s")
        assert process.returncode == 0, out[-2000:]
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(data))
    shards = [f"octax/Brix-sharded-shard{r}-v0" for r in range(2)]
    assert [minari.load_dataset(s).total_steps for s in shards] == [46, 45]
    assert cli.main(["dataset", "combine", *shards, "--dataset-id", "octax/Brix-sharded-v0"]) == 0
    assert "from 2 shards" in capsys.readouterr().out
    dataset = minari.load_dataset("octax/Brix-sharded-v0")
    assert dataset.total_steps == STEPS
    seeds = [episode_seed(dataset, i) for i in range(dataset.total_episodes)]
    assert len(set(seeds)) == len(seeds)
    env_ = dataset.recover_environment()
    for episode in dataset.iterate_episodes():
        obs, _ = env_.reset(seed=episode_seed(dataset, episode.id))
        replayed = [obs]
        rewards = []
        for action in episode.actions:
            obs, reward, *_ = env_.step(int(action))
            replayed.append(obs)
            rewards.append(reward)
        assert np.array_equal(np.stack(replayed), episode.observations) and np.allclose(rewards, episode.rewards)
    with pytest.raises(ValueError, match="same seed"):
        combine_datasets([shards[0], shards[0]], "octax/Brix-twice-v0")
    with pytest.raises(ValueError, match="already exists"):
        combine_datasets(shards, "octax/Brix-sharded-v0")
