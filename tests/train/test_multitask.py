"""`octax-gym train multitask`: one PPO agent per seed for all the games (the loop's multi-task
configuration: lane i plays game i mod G, the game's one-hot joins the features), evaluated on
each game: a row per (game, seed, evaluation), one agent file per seed.

The run read here is the one test_eval_games reads too (`tiny_run.multitask_flags`: the dodger
archive's train variants, evaluated on its test variants as well, so without the one-hot, which
eval_games refuses); the one-hot is checked on a default multi-task trainer's own first rollout."""

from __future__ import annotations

import csv

import jax
import numpy as np
import pytest

pytest.importorskip("flax")
from octax_gym.cli import main  # noqa: E402
from octax_gym.generated import load_archive  # noqa: E402
from octax_gym.jax_policy import describe, load_params  # noqa: E402
from octax_gym.train import preset  # noqa: E402
from octax_gym.train.algorithm import make_trainer  # noqa: E402
from octax_gym.train.envs import Lanes  # noqa: E402
from tiny_run import multitask_flags  # noqa: E402


def test_one_agent_plays_every_game(trained, archive):
    out = trained("multitask", *multitask_flags(archive))
    with open(out / "progress.csv", newline="") as file:
        rows = [row for row in csv.DictReader(file) if row["split"] == "train"]  # test_eval_games reads the rest
    games = [spec.id for spec in load_archive(archive, "train")]
    steps = list(dict.fromkeys(r["step"] for r in rows))  # 6 envs x 8 steps an update: evaluated at each
    assert len(steps) == 5 and [(r["game"], r["seed"], r["step"]) for r in rows] == [
        (game, seed, step) for step in steps for game in games for seed in ("0", "1")]
    # Training statistics are the agent's, shared by its games' rows.
    last = [r for r in rows if r["step"] == steps[-1]]
    assert last[0]["pg_loss"] == last[2]["pg_loss"] == last[4]["pg_loss"] and last[0]["pg_loss"] != last[1]["pg_loss"]
    assert sorted(p.name for p in (out / "agents").iterdir()) == ["multitask-seed0.msgpack", "multitask-seed1.msgpack"]
    assert describe(load_params(out / "agents" / "multitask-seed0.msgpack")).num_actions == 17


def test_lanes_alternate_games_and_masks_follow_them():
    config = preset("cpu", "multitask", games=("Airplane", "Deep8"), num_envs=4, num_minibatches=2, num_steps=8,
                    total_steps=64, env_overrides=(("max_episode_steps", 20),))
    lanes = Lanes(config.games, dict(config.env_overrides), 0)
    trainer = make_trainer(config, lanes)

    @jax.jit  # the first runner and its first rollout, in one program
    def first(key, games):
        runner = trainer.init(key, games)
        return runner, trainer.collect(runner)

    runner, (_, batch, _) = first(jax.random.key(0), np.arange(4) % 2)
    assert runner.params["params"]["Dense_0"]["kernel"].shape[0] == 1024 + 2  # the games' one-hot (game_input)
    assert np.asarray(runner.game).tolist() == [0, 1, 0, 1]
    assert np.asarray(runner.env_state.game).tolist() == [0, 1, 0, 1]
    games, legal, actions = np.asarray(batch[1]), np.asarray(batch[2]), np.asarray(batch[3])
    assert (actions[games == 0] < 2).all() and (actions[games == 1] < 4).all()  # Airplane: 2 actions, Deep8: 4
    assert (actions[games == 1] >= 2).any()
    assert (legal.sum(-1) == np.where(games == 0, 2, 4)).all()  # each lane's mask, its game's (Lanes.legal_mask)


def test_lanes_must_divide_among_the_games(capsys):
    assert main(["train", "multitask", "--games", "Airplane,Deep8,Brix", "--num-envs", "64", "--no-progress"]) == 1
    assert "num_envs = 64 must be a multiple of the 3 games" in capsys.readouterr().err
