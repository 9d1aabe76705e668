"""`eval_games` (`--eval-games`): games every agent is evaluated on but never trains on (a generated
family's held-out variants), as progress.csv rows with split "eval"; and `archive:DIR[:SPLIT]`
naming an `octax-gym generate` archive's games in `--games` and `--eval-games`."""

from __future__ import annotations

import csv

import numpy as np
import pytest

pytest.importorskip("flax")
from octax_gym.cli import main  # noqa: E402
from octax_gym.generated import load_archive  # noqa: E402
from octax_gym.jax_policy import load_params  # noqa: E402
from octax_gym.train import preset, resolve_games  # noqa: E402
from tiny_run import STEPS, TINY, multitask_flags  # noqa: E402


def _rows(out):
    with open(out / "progress.csv", newline="") as file:
        return list(csv.DictReader(file))


def test_archive_names_its_games_and_splits(archive):
    train, test = resolve_games(f"archive:{archive}:train"), resolve_games(f"archive:{archive}:test")
    assert [s.id for s in train] == [s.id for s in load_archive(archive, "train")]
    assert {s.id for s in resolve_games(f"archive:{archive}")} == {s.id for s in train + test}
    with pytest.raises(ValueError, match="no archive at"):
        resolve_games(f"archive:{archive}/nothing:train")
    with pytest.raises(ValueError, match="name the archive's folder"):
        resolve_games("archive::train")


def test_multitask_is_evaluated_on_the_held_out_variants(archive, trained):
    """The multi-task run test_multitask reads too (conftest's `archive`, `tiny_run.multitask_flags`)."""
    train, test = load_archive(archive, "train"), load_archive(archive, "test")
    out = trained("multitask", *multitask_flags(archive))  # lane i plays train variant i mod 3
    rows = _rows(out)
    assert list(rows[0])[:4] == ["game", "seed", "split", "step"]
    games = [(s.id, "train") for s in train] + [(s.id, "eval") for s in test]
    steps = list(dict.fromkeys(r["step"] for r in rows))  # 6 envs x 8 steps an update: evaluated at each
    assert len(steps) == 5 and [(r["game"], r["split"], r["seed"], r["step"]) for r in rows] == [
        (game, split, seed, step) for step in steps for game, split in games for seed in ("0", "1")]
    last = [r for r in rows if r["step"] == steps[-1]]
    # an eval row is played by its seed's one agent: the agent's training statistics, its own returns
    by_seed = {seed: {r["pg_loss"] for r in last if r["seed"] == seed} for seed in ("0", "1")}
    assert all(len(losses) == 1 for losses in by_seed.values()) and by_seed["0"] != by_seed["1"]
    assert all(np.isfinite(float(r["eval_greedy_return"])) for r in last)
    assert sorted(p.name for p in (out / "agents").iterdir()) == ["multitask-seed0.msgpack", "multitask-seed1.msgpack"]
    params = load_params(out / "agents" / "multitask-seed0.msgpack")
    assert params["params"]["Dense_0"]["kernel"].shape[0] == 1024  # no one-hot: the screen alone


@pytest.mark.slow  # two ppo runs and three programs: about 40 s on 2 idle cores, 160 s on loaded ones
def test_eval_games_leave_training_as_it_was(archive, tmp_path):
    """A ppo run on one variant with the others as eval_games trains bit for bit what it trains
    without them (the training mix is the same), and its own game's rows are the same."""
    every = load_archive(archive)
    own, others = every[0].id, [s.id for s in every[1:]]
    runs = {}
    for name, extra in (("plain", []), ("eval", ["--eval-games", ",".join(f"archive:{archive}:{g}" for g in others)])):
        runs[name] = tmp_path / name
        assert main(["train", "ppo", "--games", f"archive:{archive}:{own}", *extra, *TINY,
                     "--out-dir", str(runs[name])]) == 0
    agent = f"{own}-seed0.msgpack"
    assert sorted(p.name for p in (runs["eval"] / "agents").iterdir()) == [agent]
    plain, evaluated = (load_params(runs[name] / "agents" / agent) for name in ("plain", "eval"))
    assert all(np.array_equal(a, b) for a, b in zip(jax_leaves(plain), jax_leaves(evaluated)))
    rows = _rows(runs["eval"])
    own_rows = [r for r in rows if r["split"] == "train"]
    assert [r["game"] for r in own_rows] == [own] * len(STEPS)
    same = ("step", "eval_greedy_return", "eval_sampled_return", "pg_loss", "train_episode_return")
    assert [[r[c] for c in same] for r in own_rows] == [[r[c] for c in same] for r in _rows(runs["plain"])]
    assert [r["game"] for r in rows if r["split"] == "eval"] == others * len(STEPS)
    assert "split" not in _rows(runs["plain"])[0]  # a run without eval_games writes the columns it wrote


def jax_leaves(tree):
    import jax

    return [np.asarray(x) for x in jax.tree.leaves(tree)]


@pytest.mark.parametrize("config, message", [
    (dict(algorithm="multitask", games=("Airplane", "Deep8"), eval_games=("Brix",), num_envs=64),
     "give --no-game-input"),
    (dict(games=("Airplane", "Deep8"), eval_games=("Brix",)), "trains one game"),
    (dict(games=("Airplane",), eval_games=("Brix", "Airplane")), "also trained on"),
    (dict(games=("Airplane",), eval_games=("Brix", "Brix")), "eval_games names a game twice"),
    (dict(algorithm="selfplay", games=("Cycles",), eval_games=("Brix",)), "not of selfplay"),
])
def test_bad_eval_games_are_refused_by_name(config, message):
    algorithm = config.pop("algorithm", "ppo")
    with pytest.raises(ValueError, match=message):
        preset("cpu", algorithm, **config)


def test_an_archive_game_that_is_not_there_is_named(archive, capsys):
    assert main(["train", "ppo", "--games", f"archive:{archive}:dodger-s9-0000", "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert "'dodger-s9-0000' is no split (train, test) and no accepted game" in err and "dodger-s0-0000" in err
