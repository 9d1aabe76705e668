"""`octax-gym train multitask`: one PPO agent per seed for all the games (the loop's multi-task
configuration: lane i plays game i mod G, the game's one-hot joins the features), evaluated on
each game: a row per (game, seed, evaluation), one agent file per seed."""

from __future__ import annotations

import csv

import jax
import numpy as np
import pytest

pytest.importorskip("flax")
from octax_gym.cli import main  # noqa: E402
from octax_gym.jax_policy import describe, load_params  # noqa: E402
from octax_gym.train import preset  # noqa: E402
from octax_gym.train.algorithm import make_trainer  # noqa: E402
from octax_gym.train.envs import Lanes  # noqa: E402
from tiny_run import STEPS  # noqa: E402


def test_one_agent_plays_every_game(trained):
    out = trained("multitask", "--games", "Airplane,Deep8", "--num-seeds", "2")
    with open(out / "progress.csv", newline="") as file:
        rows = list(csv.DictReader(file))
    assert [(r["game"], r["seed"], r["step"]) for r in rows] == [
        (game, seed, str(step)) for step in STEPS for game in ("Airplane", "Deep8") for seed in ("0", "1")]
    # Training statistics are the agent's, shared by its games' rows.
    last = [r for r in rows if r["step"] == str(STEPS[-1])]
    assert last[0]["pg_loss"] == last[2]["pg_loss"] and last[0]["pg_loss"] != last[1]["pg_loss"]
    assert sorted(p.name for p in (out / "agents").iterdir()) == ["multitask-seed0.msgpack", "multitask-seed1.msgpack"]
    params = load_params(out / "agents" / "multitask-seed0.msgpack")
    assert describe(params).num_actions == 17
    assert params["params"]["Dense_0"]["kernel"].shape[0] == 1024 + 2  # the games' one-hot


def test_lanes_alternate_games_and_masks_follow_them():
    config = preset("cpu", "multitask", games=("Airplane", "Deep8"), num_envs=4, num_minibatches=2, num_steps=8,
                    total_steps=64, env_overrides=(("max_episode_steps", 20),))
    lanes = Lanes(config.games, dict(config.env_overrides), 0)
    trainer = make_trainer(config, lanes)
    runner = jax.jit(trainer.init)(jax.random.key(0), np.arange(4) % 2)
    assert np.asarray(runner.game).tolist() == [0, 1, 0, 1]
    assert np.asarray(runner.env_state.game).tolist() == [0, 1, 0, 1]
    runner, batch, _ = jax.jit(trainer.collect)(runner)
    games, legal, actions = np.asarray(batch[1]), np.asarray(batch[2]), np.asarray(batch[3])
    assert (actions[games == 0] < 2).all() and (actions[games == 1] < 4).all()  # Airplane: 2 actions, Deep8: 4
    assert (actions[games == 1] >= 2).any()
    assert (legal.sum(-1) == np.where(games == 0, 2, 4)).all()  # each lane's mask, its game's (Lanes.legal_mask)


def test_lanes_must_divide_among_the_games(capsys):
    assert main(["train", "multitask", "--games", "Airplane,Deep8,Brix", "--num-envs", "64", "--no-progress"]) == 1
    assert "num_envs = 64 must be a multiple of the 3 games" in capsys.readouterr().err
