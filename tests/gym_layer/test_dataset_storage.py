"""Compact datasets (octax_gym/datasets/storage.py) and the transition loader (transitions.py).

The observations go through HDF5's scale-offset and deflate filters: these tests check that
`minari.load_dataset` gives every byte back (synthetic frames of every value range, and real
collections of the three platforms replayed in the recovered env), that the filters are really on
and make a step at least 20x smaller than plain storage, that a writer stopped between flushes
leaves a readable dataset, and that the loader's batches are the stored steps.

Every Brix collection here runs 3 envs, as test_datasets' do, so they share one compiled step.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

minari = pytest.importorskip("minari")
h5py = pytest.importorskip("h5py")

from gymnasium import spaces  # noqa: E402

from octax_gym.datasets import (DatasetWriter, EpisodeRecord, collect_dataset, episode_seed,  # noqa: E402
                                load_transitions, recovery_spec)
from octax_gym.datasets import storage  # noqa: E402


@pytest.fixture(autouse=True)
def datasets_path(tmp_path, monkeypatch):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    return tmp_path / "minari"


def synthetic_episode(rng, seed: int, steps: int, shape, high: int, scale: int = 1) -> EpisodeRecord:
    """Random frames with values 0..high (times scale), random actions, rewards and infos."""
    def frame():
        return (rng.integers(0, high + 1, shape) * scale).astype(np.uint8)

    episode = EpisodeRecord(seed, frame(), {"score": np.float32(0), "lives": np.int32(3), "episode_step": np.int32(0)})
    for t in range(steps):
        episode.add(int(rng.integers(0, 5)), frame(), float(rng.normal()), t == steps - 1 and seed % 2 == 0, False,
                    {"score": np.float32(t), "lives": np.int32(3), "episode_step": np.int32(t + 1)})
    return episode


@pytest.mark.parametrize("shape, high, scale", [
    ((4, 32, 64), 1, 1),      # CHIP-8 pixels
    ((4, 32, 64), 1, 255),    # obs_scale=255
    ((4, 64, 128), 1, 1),     # SUPER-CHIP
    ((4, 64, 128), 3, 1),     # XO-CHIP's four colours
    ((2, 32, 64), 255, 1),    # any byte at all
], ids=["chip8", "chip8-255", "schip", "xochip", "bytes"])
def test_every_value_range_comes_back_bit_for_bit_through_minari(shape, high, scale):
    rng = np.random.default_rng(high + scale + shape[1])
    space = spaces.Box(0, high * scale, shape, np.uint8)
    writer = DatasetWriter("octax/Synthetic-v0", recovery_spec("octax/Brix-v0", {}), space, spaces.Discrete(5),
                           flush_steps=100, metadata={"algorithm_name": "synthetic"})
    # 1 step, a chunk exactly, a chunk and one more, several chunks
    lengths = [1, storage.CHUNK_STEPS - 1, storage.CHUNK_STEPS, 2 * storage.CHUNK_STEPS + 5]
    written = [synthetic_episode(rng, seed, steps, shape, high, scale) for seed, steps in enumerate(lengths)]
    for i, episode in enumerate(written):
        writer.add(episode, cut=i == len(written) - 1)
    writer.close()
    dataset = minari.load_dataset("octax/Synthetic-v0")
    assert dataset.total_episodes == len(lengths) and dataset.total_steps == sum(lengths)
    for i, (episode, stored) in enumerate(zip(written, dataset.iterate_episodes())):
        arrays = episode.arrays(cut=i == len(written) - 1)
        assert stored.observations.dtype == np.uint8 and stored.observations.shape == arrays["observations"].shape
        assert np.array_equal(stored.observations, arrays["observations"])
        for name in ("actions", "rewards", "terminations", "truncations"):
            assert np.array_equal(getattr(stored, name), arrays[name]), name
        for name, values in arrays["infos"].items():
            assert np.array_equal(stored.infos[name], values), name
        assert episode_seed(dataset, i) == i


def test_the_observations_are_filtered_and_the_metadata_says_so(datasets_path):
    result = collect_dataset("Brix", "octax/Brix-filters-v0", 60, num_envs=3, progress=False)
    with h5py.File(result.path / "data" / "main_data.hdf5") as file:
        observations = file["episode_0"]["observations"]
        assert observations.compression == "gzip" and observations.scaleoffset == 0
        assert observations.chunks[0] <= storage.CHUNK_STEPS
    metadata = json.loads((result.path / "data" / "metadata.json").read_text())
    assert metadata["observation_filters"] == storage.FILTERS_NAME
    assert metadata["data_format"] == "hdf5" and metadata["jpeg_encoding"] is False
    assert metadata["total_steps"] == 60


def test_a_brix_step_is_at_least_20x_smaller_than_plain_storage(datasets_path):
    def bytes_per_step(dataset_id, compress):
        result = collect_dataset("Brix", dataset_id, 400, num_envs=3, seed=3, progress=False, compress=compress)
        return sum(f.stat().st_size for f in result.path.rglob("*") if f.is_file()) / result.steps, result

    plain, plain_result = bytes_per_step("octax/Brix-plain-v0", False)
    compact, compact_result = bytes_per_step("octax/Brix-compact-v0", True)
    assert plain >= 8192, plain  # a step's observation alone is 4 x 32 x 64 bytes
    assert plain / compact >= 20, (plain, compact)
    for a, b in zip(plain_result.dataset.iterate_episodes(), compact_result.dataset.iterate_episodes()):
        assert np.array_equal(a.observations, b.observations) and np.array_equal(a.actions, b.actions)


# SUPER-CHIP (4, 64, 128) and XO-CHIP (four values) games: 30 s of compiles, so CI's test-slow runs
# them; the synthetic round trip above covers their value ranges in `make test`.
@pytest.mark.slow
@pytest.mark.parametrize("game", ["Snake", "FlutterBy"])
def test_other_platforms_collect_and_replay_bit_for_bit(game):
    result = collect_dataset(game, f"octax/{game}-replay-v0", 24, num_envs=2, seed=11, progress=False,
                             max_episode_steps=10)
    dataset = minari.load_dataset(f"octax/{game}-replay-v0")
    env = dataset.recover_environment()
    assert dataset.observation_space == env.observation_space and env.observation_space.shape == (4, 64, 128)
    for episode in dataset.iterate_episodes():
        obs, _ = env.reset(seed=episode_seed(dataset, episode.id))
        replayed = [obs]
        for action in episode.actions:
            replayed.append(env.step(int(action))[0])
        assert np.array_equal(episode.observations, np.stack(replayed)), (game, episode.id)
    assert result.steps == 24


def test_a_writer_stopped_between_flushes_leaves_the_episodes_written_so_far(datasets_path):
    rng = np.random.default_rng(0)
    space = spaces.Box(0, 1, (4, 32, 64), np.uint8)
    writer = DatasetWriter("octax/Stopped-v0", recovery_spec("octax/Brix-v0", {}), space, spaces.Discrete(5),
                           flush_steps=10, metadata={})
    for seed in range(3):
        writer.add(synthetic_episode(rng, seed, 10, space.shape, 1), cut=False)  # each flushes
    writer.add(synthetic_episode(rng, 3, 5, space.shape, 1), cut=False)  # pending, never written
    del writer  # the process dies here: no close
    dataset = minari.load_dataset("octax/Stopped-v0")
    assert dataset.total_episodes == 3 and dataset.total_steps == 30
    assert [len(e) for e in dataset.iterate_episodes()] == [10, 10, 10]


# --- the loader -----------------------------------------------------------------------------


@pytest.fixture
def brix(datasets_path):
    collect_dataset("Brix", "octax/Brix-loader-v0", 150, num_envs=3, seed=5, progress=False, max_episode_steps=20)
    return minari.load_dataset("octax/Brix-loader-v0")


def test_the_loader_holds_every_stored_step_in_order(brix):
    data = load_transitions("octax/Brix-loader-v0")
    assert len(data) == brix.total_steps == 150
    assert data.observations.shape == (150 + brix.total_episodes, 4, 32, 64)
    step = 0
    for episode in brix.iterate_episodes():
        for t in range(len(episode)):
            batch = data.batch(np.array([step]))
            assert np.array_equal(batch.obs[0], episode.observations[t])
            assert np.array_equal(batch.next_obs[0], episode.observations[t + 1])
            assert batch.action[0] == episode.actions[t] and batch.reward[0] == episode.rewards[t]
            assert batch.terminated[0] == episode.terminations[t] and batch.truncated[0] == episode.truncations[t]
            assert data.episode_ids[step] == episode.id
            step += 1
    assert step == 150
    assert data.actions.dtype == np.int32 and data.rewards.dtype == np.float32


def test_sampled_batches_are_stored_steps_on_the_host_and_in_jit(brix):
    import jax

    data = load_transitions(brix, episode_indices=[2, 0])  # a chosen subset, in that order
    episodes = {e.id: e for e in brix.iterate_episodes([0, 2])}
    assert len(data) == len(episodes[2]) + len(episodes[0]) and list(np.unique(data.episode_ids)) == [0, 2]
    batch = data.sample(np.random.default_rng(1), 64)
    assert batch.obs.shape == (64, 4, 32, 64) and batch.done.dtype == np.bool_

    def check(batch):
        for i in range(len(batch.action)):
            match = [(e, t) for e in episodes.values() for t in range(len(e))
                     if np.array_equal(e.observations[t], batch.obs[i]) and e.actions[t] == batch.action[i]
                     and np.array_equal(e.observations[t + 1], batch.next_obs[i])]
            assert match, i

    check(batch)
    on_device = data.device_put()
    sample = jax.jit(lambda d, key: d.sample(key, 32))
    device_batch = jax.device_get(sample(on_device, jax.random.key(4)))
    indices = np.asarray(jax.random.randint(jax.random.key(4), (32,), 0, len(data)))
    for got, want in zip(device_batch, data.batch(indices)):
        assert np.array_equal(got, want)
    check(device_batch)
