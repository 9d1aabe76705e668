"""Offline datasets (octax_gym/datasets.py): collect with batched lanes, load with Minari, replay by seed.

One small Brix dataset (3 lanes, 331 steps, episodes truncated at 35 steps; Brix ends at the
first lost ball, which a random player loses after 33 or 37 steps, so some episodes terminate and
some are truncated) is collected once and read by most tests; every collection here uses
3 lanes, so the tests share one compiled program. Minari writes under a temporary
MINARI_DATASETS_PATH, never under HOME.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

minari = pytest.importorskip("minari")

from octax_gym import InvalidActionError  # noqa: E402
from octax_gym.datasets import collect_dataset, episode_seed  # noqa: E402

GAME, ENVS, STEPS, SEED, MAX_STEPS = "Brix", 3, 331, 7, 35  # 331 = 3 * 110 + 1: the last step fills one lane
DATASET_ID = "octax/Brix-test-v0"


@pytest.fixture(scope="module", autouse=True)
def datasets_path(tmp_path_factory):
    with pytest.MonkeyPatch.context() as patch:
        path = tmp_path_factory.mktemp("minari")
        patch.setenv("MINARI_DATASETS_PATH", str(path))
        yield path


@pytest.fixture(scope="module")
def collected(datasets_path):
    return collect_dataset(GAME, DATASET_ID, STEPS, num_envs=ENVS, seed=SEED, progress=False,
                           max_episode_steps=MAX_STEPS)


@pytest.fixture(scope="module")
def dataset(collected):
    return minari.load_dataset(DATASET_ID)


@pytest.fixture(scope="module")
def episodes(dataset):
    return list(dataset.iterate_episodes())


def cut_at_stop(episode) -> bool:
    """Stopped by the end of collection: truncated before the env's own bound, not terminated."""
    return (bool(episode.truncations[-1]) and not episode.terminations[-1]
            and episode.infos["episode_step"][-1] < MAX_STEPS)


def replay(env, dataset, episode):
    """Plays an episode's actions from its seed in `env`; returns what the env gave, stacked like the episode."""
    obs, info = env.reset(seed=episode_seed(dataset, episode.id))
    observations, rewards, terminations, truncations = [obs], [], [], []
    infos = {name: [value] for name, value in info.items()}
    for action in episode.actions:
        obs, reward, terminated, truncated, info = env.step(int(action))
        observations.append(obs)
        rewards.append(reward)
        terminations.append(terminated)
        truncations.append(truncated)
        for name, value in info.items():
            infos[name].append(value)
    return (np.stack(observations), np.array(rewards, np.float32), np.array(terminations), np.array(truncations),
            {name: np.array(values) for name, values in infos.items()})


# --- the round trip ---------------------------------------------------------------------------


def test_every_episode_replays_exactly_from_its_seed_in_the_recovered_env(dataset, episodes):
    env = dataset.recover_environment()
    later = [e for e in episodes if episode_seed(dataset, e.id) >= SEED + ENVS]  # not the first in their lane
    assert later and any(e.terminations[-1] for e in later) and any(e.truncations[-1] and not cut_at_stop(e)
                                                                   for e in later)
    for episode in episodes:
        observations, rewards, terminations, truncations, infos = replay(env, dataset, episode)
        assert observations.dtype == np.uint8
        np.testing.assert_array_equal(observations, episode.observations)
        np.testing.assert_array_equal(rewards, episode.rewards)
        np.testing.assert_array_equal(terminations, episode.terminations)
        for name in ("score", "lives", "episode_step"):
            np.testing.assert_array_equal(infos[name], episode.infos[name])
        if cut_at_stop(episode):  # the env went on; only the dataset marks the cut
            assert not truncations[-1]
            truncations[-1] = True
        np.testing.assert_array_equal(truncations, episode.truncations)
    env.close()


def test_the_recovered_env_is_the_registered_one_with_the_collection_options(dataset):
    assert dataset.spec.env_spec.id == "octax/Brix-v0"
    assert dataset.spec.env_spec.kwargs == {"game": GAME, "max_episode_steps": MAX_STEPS}
    env = dataset.recover_environment()
    assert env.spec.max_episode_steps == MAX_STEPS  # where the recovered env cuts episodes, as collected
    assert env.unwrapped.game_spec.id == GAME
    env.close()


def test_observations_are_stored_exactly_as_uint8(dataset, episodes, collected):
    assert dataset.storage.metadata["jpeg_encoding"] is False
    assert dataset.observation_space.dtype == np.uint8 and dataset.observation_space.shape == (4, 32, 64)
    for episode in episodes:
        assert episode.observations.dtype == np.uint8
        assert episode.observations.shape == (len(episode) + 1, 4, 32, 64)
        assert set(np.unique(episode.observations)) <= {0, 1}
    assert collected.path.joinpath("data", "main_data.hdf5").is_file()


def test_steps_add_up_and_episodes_end_only_at_their_last_step(dataset, episodes, collected):
    assert dataset.total_steps == collected.steps == sum(len(e) for e in episodes) == STEPS
    assert dataset.total_episodes == collected.episodes == len(episodes)
    for episode in episodes:
        ended = episode.terminations | episode.truncations
        assert ended[-1] and not ended[:-1].any()
        assert len(episode.actions) == len(episode.rewards) == len(episode) <= MAX_STEPS


def test_the_episodes_running_at_the_stop_are_stored_truncated(dataset, episodes):
    cut = [e for e in episodes if cut_at_stop(e)]
    assert 1 <= len(cut) <= ENVS  # one per lane, unless a lane's episode ended at the very last step
    assert [e.id for e in episodes[-len(cut):]] == [e.id for e in cut]  # written last
    assert max(episode_seed(dataset, e.id) for e in cut) == SEED + len(episodes) - 1  # started last


def test_infos_hold_score_lives_and_episode_step_from_the_reset_on(episodes):
    for episode in episodes:
        assert set(episode.infos) == {"score", "lives", "episode_step"}
        np.testing.assert_array_equal(episode.infos["episode_step"], np.arange(len(episode) + 1))
        assert episode.infos["lives"][0] == 5 and (episode.infos["lives"] >= 0).all()
        np.testing.assert_allclose(np.diff(episode.infos["score"]), episode.rewards)


def test_each_episode_has_its_own_seed_one_after_another_from_the_given_one(dataset, episodes):
    seeds = [episode_seed(dataset, e.id) for e in episodes]
    assert sorted(seeds) == list(range(SEED, SEED + len(episodes)))
    assert next(iter(dataset.storage.get_episode_metadata([0])))["seed"] == seeds[0]  # Minari's episode metadata


def test_the_same_seed_gives_the_same_dataset(dataset, episodes):
    again = collect_dataset(GAME, "octax/Brix-test-again-v0", STEPS, num_envs=ENVS, seed=SEED, progress=False,
                            max_episode_steps=MAX_STEPS).dataset
    for first, second in zip(episodes, again.iterate_episodes(), strict=True):
        for field in ("observations", "actions", "rewards", "terminations", "truncations"):
            np.testing.assert_array_equal(getattr(first, field), getattr(second, field))
        assert episode_seed(again, second.id) == episode_seed(dataset, first.id)


def test_a_policy_function_gets_the_batched_observations_and_its_actions_are_stored():
    seen = []

    def press_first_key(obs):
        seen.append((type(obs), obs.dtype, obs.shape))
        return np.ones(len(obs), np.int32)

    result = collect_dataset(GAME, "octax/Brix-ones-v0", 30, num_envs=ENVS, policy=press_first_key, seed=0,
                             progress=False, max_episode_steps=MAX_STEPS)
    assert set(seen) == {(np.ndarray, np.dtype(np.uint8), (ENVS, 4, 32, 64))} and len(seen) == 10
    episodes = list(result.dataset.iterate_episodes())
    assert all((e.actions == 1).all() for e in episodes) and sum(len(e) for e in episodes) == 30
    assert result.dataset.storage.metadata["algorithm_name"].endswith("press_first_key")


def test_overwrite_replaces_a_dataset(datasets_path):
    collect_dataset(GAME, "octax/Brix-twice-v0", 6, num_envs=ENVS, policy="noop", progress=False)
    with pytest.raises(ValueError, match="already exists.*overwrite=True"):
        collect_dataset(GAME, "octax/Brix-twice-v0", 6, num_envs=ENVS, progress=False)
    result = collect_dataset(GAME, "octax/Brix-twice-v0", 9, num_envs=ENVS, policy="noop", progress=False,
                             overwrite=True)
    assert minari.load_dataset("octax/Brix-twice-v0").total_steps == result.steps == 9


# --- bad input --------------------------------------------------------------------------------


@pytest.mark.parametrize("change, message", [
    ({"env_id": "NoSuchGame"}, r"unknown game 'NoSuchGame'; valid: .*'Brix', .*or their Gymnasium ids"),
    ({"num_steps": 0}, r"num_steps must be an int >= 1"),
    ({"num_envs": 0}, r"num_envs must be an int >= 1"),
    ({"seed": -1}, r"seed must be an int in 0\.\."),
    ({"dataset_id": "octax/Brix"}, r"dataset_id must look like 'namespace/name-v0'.*-vN"),
    ({"dataset_id": "octax/Brix v0"}, r"dataset_id must look like"),
    ({"policy": "greedy"}, r"unknown policy 'greedy'; valid: None, 'random', 'noop'"),
    ({"max_episode_step": 10}, r"unknown env option\(s\) \['max_episode_step'\] \(did you mean "
                               r"'max_episode_steps'\?\); valid: .*'max_episode_steps'"),
])
def test_bad_arguments_name_the_valid_choices(change, message, datasets_path):
    arguments = {"env_id": GAME, "dataset_id": "octax/Brix-bad-v0", "num_steps": 6, "num_envs": ENVS,
                 "progress": False, **change}
    with pytest.raises(ValueError, match=message):
        collect_dataset(**arguments)
    assert not (datasets_path / "octax" / "Brix-bad-v0").exists()


@pytest.mark.parametrize("actions, error, message", [
    (lambda n: np.ones((n, 1), np.int64), ValueError,
     r"Brix, from the policy: actions must have shape \(3,\), one per env, got \(3, 1\)"),
    (lambda n: np.ones(n - 1, np.int64), ValueError, r"got \(2,\)"),
    (lambda n: np.ones(n, np.float32), TypeError, r"actions must be integers, got float32"),
    (lambda n: np.full(n, 3), InvalidActionError,
     r"Brix, from the policy: action 3 is out of range; valid actions are 0\.\.2"),
    (lambda n: np.full(n, -1), InvalidActionError, r"action -1 is out of range"),
])
def test_a_policy_returning_bad_actions_fails_and_leaves_no_dataset(actions, error, message, datasets_path):
    with pytest.raises(error, match=message):
        collect_dataset(GAME, "octax/Brix-bad-v0", 6, num_envs=ENVS, policy=lambda obs: actions(len(obs)),
                        progress=False)
    assert not (datasets_path / "octax" / "Brix-bad-v0").exists()


def test_an_existing_dataset_is_not_touched_without_overwrite(collected):
    with pytest.raises(ValueError, match=r"'octax/Brix-test-v0' already exists .*pick another name or version"):
        collect_dataset(GAME, DATASET_ID, 6, num_envs=ENVS, progress=False)
    assert minari.load_dataset(DATASET_ID).total_steps == STEPS


def test_without_minari_import_octax_gym_works_and_collecting_names_the_extra():
    code = ("import sys; sys.modules['minari'] = None\n"  # makes `import minari` raise ImportError
            "import octax_gym, octax_gym.datasets, octax_gym.cli\n"
            "try:\n"
            "    octax_gym.datasets.collect_dataset('Brix', 'octax/x-v0', 1)\n"
            "except ImportError as exc:\n"
            "    print(exc)\n")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert 'pip install "octax-gym[datasets]"' in result.stdout
