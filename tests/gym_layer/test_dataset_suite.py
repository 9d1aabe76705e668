"""The dataset suite (octax_gym/datasets/suite.py): which checkpoint is medium and which expert,
and a test-sized suite built from a fake `octax-gym train ppo --save-at-evals` run whose params are
a freshly initialised network of the trainer (what the suite does with trained ones; tests/train/
test_save_at_evals.py picks from a real run): three datasets per game, each naming its policy in
its metadata with the params beside it."""

from __future__ import annotations

import csv
import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

minari = pytest.importorskip("minari")
flax = pytest.importorskip("flax", reason="the suite's policies are the trainer's (the train extra)")

from octax_gym import UnknownOptionError, jax_policy  # noqa: E402
from octax_gym.datasets import suite  # noqa: E402


def fake_run(folder: Path, evals: dict[int, float], random_return: float = 1.0, game: str = "Flak",
             params: bytes = b"", seed: int = 0) -> Path:
    """A training run's files as `octax-gym train ppo --games <game> --seed <seed> --save-at-evals` writes
    them, with a second seed's agent and a second game's beside it (the suite must read its own)."""
    (folder / "agents").mkdir(parents=True, exist_ok=True)
    (folder / "config.json").write_text(json.dumps({
        "algorithm": "ppo", "eval_envs": 64, "games": [game, "Other"], "seed": seed, "num_seeds": 2,
        "save_at_evals": True, "command": ["octax-gym", "train", "ppo", "--games", f"{game},Other"]}))
    with open(folder / "progress.csv", "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=["game", "seed", "step", "eval_mean_return", "random_mean_return"])
        writer.writeheader()
        for step, value in evals.items():
            for other_game, other_seed, shift in ((game, seed, 0.0), (game, seed + 1, 7.0), ("Other", seed, 3.0)):
                writer.writerow({"game": other_game, "seed": other_seed, "step": step, "eval_mean_return": value + shift,
                                 "random_mean_return": random_return})
    for name in (f"{game}-seed{seed}", f"{game}-seed{seed + 1}", f"Other-seed{seed}"):
        for step in evals:
            (folder / "agents" / f"{name}-step{step}.msgpack").write_bytes(params or f"{name} step {step}".encode())
        (folder / "agents" / f"{name}.msgpack").write_bytes(params or f"{name} final".encode())
    return folder


def test_medium_is_the_checkpoint_nearest_a_third_of_the_way_and_expert_the_final_one(tmp_path):
    # random 1, expert 10: a third of the way is 4; 3.5 is nearer than 5.0
    run = fake_run(tmp_path / "run", {0: 1.0, 100: 2.0, 200: 3.5, 300: 5.0, 400: 9.0, 500: 10.0}, seed=3)
    # the untrained network is never the medium policy, even when nearest the target
    early = fake_run(tmp_path / "early", {0: -5.0, 100: -0.9, 200: -0.8}, random_return=-5.0, game="Squash")
    assert suite.pick_policies(early, "Squash")["medium"].steps_trained == 100
    cards = suite.pick_policies(run, "Flak")
    assert cards["expert"].steps_trained == 500 and cards["expert"].eval_return == 10.0
    assert cards["expert"].params_path == run / "agents" / "Flak-seed3.msgpack"
    assert cards["medium"].steps_trained == 200 and cards["medium"].eval_return == 3.5
    assert cards["medium"].params_path == run / "agents" / "Flak-seed3-step200.msgpack"
    card = cards["medium"].metadata()
    assert card["algorithm"] == "PPO" and card["random_return"] == 1.0 and card["eval_episodes"] == 64
    assert card["params_sha256"] == hashlib.sha256(b"Flak-seed3 step 200").hexdigest()
    assert "--games Flak,Other" in card["training_command"]


def test_a_run_per_game_or_one_for_all(tmp_path):
    fake_run(tmp_path / "each" / "Flak", {0: 1.0, 100: 2.0})
    assert suite.run_for(tmp_path / "each", "Flak") == tmp_path / "each" / "Flak"
    fake_run(tmp_path / "all", {0: 1.0, 100: 2.0})
    assert suite.run_for(tmp_path / "all", "Flak") == tmp_path / "all"


def test_a_missing_run_names_the_training_command(tmp_path):
    with pytest.raises(FileNotFoundError, match="octax-gym train ppo --games Airplane --save-at-evals"):
        suite.pick_policies(tmp_path / "Airplane", "Airplane")
    # a run without the game's agent, or without its agents kept at every evaluation
    run = fake_run(tmp_path / "run", {0: 1.0, 100: 2.0})
    with pytest.raises(FileNotFoundError, match="holds no Airplane-seed0 agent"):
        suite.pick_policies(run, "Airplane")
    for path in (run / "agents").glob("Flak-seed0-step*.msgpack"):
        path.unlink()
    with pytest.raises(FileNotFoundError, match="--save-at-evals"):
        suite.pick_policies(run, "Flak")
    with pytest.raises(UnknownOptionError, match="Airplane"):
        suite.build_suite(tmp_path, games=["Pong"])
    with pytest.raises(UnknownOptionError, match="expert"):
        suite.build_suite(tmp_path, games=["Flak"], kinds=["novice"])


def test_a_test_sized_suite_names_its_policies_and_keeps_their_params(tmp_path, monkeypatch):
    import jax

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    from octax_gym.train.networks import ActorCritic

    params = ActorCritic().init(jax.random.key(0), np.zeros((1, 4, 32, 64), np.uint8))  # the trainer's 17-wide agent
    fake_run(tmp_path / "runs", {0: 10.0, 32768: 20.0, 65536: 40.0},
             params=flax.serialization.to_bytes(params), random_return=10.0)
    results = suite.build_suite(tmp_path / "runs", games=["Flak"], steps=40, num_envs=4, progress=False)
    assert [r.dataset_id for r in results] == ["octax/Flak/random-v0", "octax/Flak/medium-v0", "octax/Flak/expert-v0"]
    for result, kind in zip(results, suite.KINDS):
        dataset = minari.load_dataset(result.dataset_id)
        assert dataset.total_steps == 40
        metadata = json.loads((result.path / "data" / "metadata.json").read_text())
        assert metadata["suite"] == {"game": "Flak", "kind": kind}
        assert metadata["observation_filters"] == "scaleoffset+gzip1"
        assert json.loads(dataset.spec.env_spec.to_json())["kwargs"]["max_episode_steps"] == suite.EVAL_MAX_STEPS
        if kind == "random":
            assert metadata["policy"] is None and metadata["algorithm_name"] == "random"
            continue
        policy = metadata["policy"]
        assert metadata["algorithm_name"] == f"PPO-{kind}"
        assert policy["steps_trained"] == {"medium": 32768, "expert": 65536}[kind]
        assert policy["eval_return"] == {"medium": 20.0, "expert": 40.0}[kind]
        kept = result.path / policy["params_file"]
        assert hashlib.sha256(kept.read_bytes()).hexdigest() == policy["params_sha256"]
        assert jax_policy.describe(jax_policy.load_params(kept)) == ("actor_critic", 4, 17, False, "image")
    # the policies' actions are the network's samples, not the random ones
    random_actions = np.concatenate([e.actions for e in minari.load_dataset("octax/Flak/random-v0").iterate_episodes()])
    expert_actions = np.concatenate([e.actions for e in minari.load_dataset("octax/Flak/expert-v0").iterate_episodes()])
    assert not np.array_equal(random_actions, expert_actions)


def test_sampling_policy_draws_from_the_networks_softmax(tmp_path):
    import jax

    from octax_gym.train.networks import ActorCritic

    network = ActorCritic(3)
    params = network.init(jax.random.key(1), np.zeros((1, 4, 32, 64), np.uint8))
    # push the policy hard towards action 2 through the last layer's bias
    params["params"]["Dense_1"]["bias"] = np.array([0.0, 0.0, 3.0], np.float32)  # p = e^3 / (e^3 + 2) = 0.91
    path = tmp_path / "params.msgpack"
    path.write_bytes(flax.serialization.to_bytes(params))
    act = jax_policy.sampling_policy(jax_policy.load_params(path), seed=3)
    obs = np.random.default_rng(0).integers(0, 2, (256, 4, 32, 64), dtype=np.uint8)
    first, second = act(obs), act(obs)
    assert first.shape == (256,) and first.dtype == np.int32
    assert 0.85 < np.mean(first == 2) < 0.97 and not np.array_equal(first, second)  # sampled, and the key moves on
    again = jax_policy.sampling_policy(jax_policy.load_params(path), seed=3)
    assert np.array_equal(again(obs), first)  # the same seed, the same actions


def test_a_q_networks_policy_is_epsilon_greedy_not_its_softmax(tmp_path):
    """A PQN agent plays what its sampled evaluation plays: the argmax of its Q-values, a random
    legal action at eval_epsilon. The softmax of Q-values (close together) would be near uniform."""
    import jax

    from octax_gym.train.networks import ActorCritic, QNetwork

    params = QNetwork().init(jax.random.key(1), np.zeros((1, 4, 32, 64), np.uint8))
    bias = np.zeros(17, np.float32)
    bias[2] = 0.5  # Q(2) leads by 0.5: the softmax over the game's 5 actions would pick it 29% of the time
    params["params"]["Dense_1"]["bias"] = bias
    kernel = np.asarray(params["params"]["Dense_1"]["kernel"])
    params["params"]["Dense_1"]["kernel"] = np.zeros_like(kernel)  # every observation: the bias alone
    path = tmp_path / "q.msgpack"
    path.write_bytes(flax.serialization.to_bytes(params))
    obs = np.random.default_rng(0).integers(0, 2, (4096, 4, 32, 64), dtype=np.uint8)
    act = jax_policy.sampling_policy(jax_policy.load_params(path), seed=3, num_actions=5)
    actions = act(obs)
    assert actions.dtype == np.int32 and set(np.unique(actions)) <= set(range(5))  # the game's 5 actions only
    assert 0.98 < np.mean(actions == 2) < 1.0  # greedy, but 0.5% of rows draw (4 in 5 of them another action)
    explored = jax_policy.sampling_policy(jax_policy.load_params(path), seed=3, num_actions=5, epsilon=0.5)(obs)
    assert 0.55 < np.mean(explored == 2) < 0.65  # 0.5 + 0.5 / 5
    with pytest.raises(ValueError, match="epsilon=1.5: a probability"):
        jax_policy.sampling_policy(jax_policy.load_params(path), seed=3, epsilon=1.5)
    actor_critic = tmp_path / "ppo.msgpack"
    actor_critic.write_bytes(flax.serialization.to_bytes(ActorCritic(3).init(jax.random.key(1), obs[:1])))
    with pytest.raises(ValueError, match="epsilon=0.1: an actor-critic's actions are sampled"):
        jax_policy.sampling_policy(jax_policy.load_params(actor_critic), seed=3, epsilon=0.1)
