"""`octax-gym dataset collect` (octax_gym/cli/dataset.py): writes a Minari dataset and prints a summary.

Run in-process through `cli.main` with 3 lanes of Brix (the batch size tests/gym_layer/test_datasets.py
compiles too); every dataset goes under tmp_path, by --data-path or MINARI_DATASETS_PATH.
"""

from __future__ import annotations

import os
import re

import pytest

minari = pytest.importorskip("minari")

from octax_gym import cli  # noqa: E402

SUMMARY = re.compile(r"wrote (?P<id>\S+): (?P<episodes>\d+) episodes, (?P<steps>\d+) steps in [\d.]+ s "
                     r"\([\d,]+ steps/s\), [\d,.]+ MB at (?P<path>.+)$")


@pytest.fixture(autouse=True)
def home_untouched(tmp_path, monkeypatch):
    """MINARI_DATASETS_PATH points into tmp_path, so nothing can reach ~/.minari."""
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "default"))


def collect(*arguments: str) -> int:
    return cli.main(["dataset", "collect", "Brix", "--envs", "3", "--no-progress", *arguments])


def test_collect_writes_under_data_path_and_prints_a_summary(tmp_path, capsys, monkeypatch):
    data = tmp_path / "data"
    assert collect("--dataset-id", "octax/Brix-cli-v0", "--steps", "100", "--max-episode-steps", "20",
                   "--seed", "3", "--data-path", str(data)) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    summary = SUMMARY.match(line)
    assert summary, line
    assert summary["id"] == "octax/Brix-cli-v0" and summary["steps"] == "100"
    assert summary["path"] == str(data / "octax" / "Brix-cli-v0")
    assert os.environ["MINARI_DATASETS_PATH"] == str(tmp_path / "default")  # restored after the command
    assert not (tmp_path / "default" / "octax").exists()

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(data))
    dataset = minari.load_dataset("octax/Brix-cli-v0")
    assert dataset.total_steps == 100 and dataset.total_episodes == int(summary["episodes"]) >= 5
    assert dataset.spec.env_spec.kwargs == {"game": "Brix", "max_episode_steps": 20}
    assert next(iter(dataset.storage.get_episode_metadata([0])))["seed"] in (3, 4, 5)


def test_collect_defaults_to_minari_datasets_path_and_takes_the_noop_policy(tmp_path, capsys):
    assert collect("--dataset-id", "octax/Brix-noop-v0", "--steps", "12", "--policy", "noop") == 0
    assert capsys.readouterr().out.rstrip().endswith(str(tmp_path / "default" / "octax" / "Brix-noop-v0"))
    dataset = minari.load_dataset("octax/Brix-noop-v0")
    assert all((episode.actions == 0).all() for episode in dataset.iterate_episodes())
    assert dataset.storage.metadata["algorithm_name"] == "noop"


def test_an_existing_dataset_fails_unless_overwrite(capsys):
    assert collect("--dataset-id", "octax/Brix-twice-v0", "--steps", "3") == 0
    assert collect("--dataset-id", "octax/Brix-twice-v0", "--steps", "3") == 1
    assert "already exists" in capsys.readouterr().err
    assert collect("--dataset-id", "octax/Brix-twice-v0", "--steps", "6", "--overwrite") == 0
    assert minari.load_dataset("octax/Brix-twice-v0").total_steps == 6


@pytest.mark.parametrize("arguments, message", [
    (["--dataset-id", "octax/Brix-v0", "--steps", "0"], "num_steps must be an int >= 1"),
    (["--dataset-id", "Brix", "--steps", "5"], "dataset_id must look like 'namespace/name-v0'"),
    (["--dataset-id", "octax/Brix-v0", "--steps", "5", "--policy", "smart"], "valid: None, 'random', 'noop'"),
])
def test_bad_arguments_exit_1_with_the_valid_choices(arguments, message, capsys):
    assert collect(*arguments) == 1
    assert message in capsys.readouterr().err


def test_an_unknown_game_exits_1_listing_the_games(capsys):
    assert cli.main(["dataset", "collect", "Brixx", "--dataset-id", "octax/x-v0", "--steps", "5"]) == 1
    err = capsys.readouterr().err
    assert "unknown game 'Brixx'" in err and "Brix" in err and "Pong" in err


def test_dataset_without_an_action_shows_its_help(capsys):
    assert cli.main(["dataset"]) == 2
    assert "collect" in capsys.readouterr().out


def test_collect_requires_an_id_and_steps(capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["dataset", "collect", "Brix", "--steps", "5"])
    assert exit_info.value.code == 2 and "--dataset-id" in capsys.readouterr().err


def test_progress_bar_shows_unless_no_progress(tmp_path, capsys):
    assert cli.main(["dataset", "collect", "Brix", "--envs", "3", "--dataset-id", "octax/Brix-bar-v0",
                     "--steps", "6"]) == 0
    assert "collecting octax/Brix-v0" in capsys.readouterr().err
    assert minari.load_dataset("octax/Brix-bar-v0").total_steps == 6


def test_suite_collects_random_datasets_and_names_a_missing_training_run(tmp_path, capsys):
    data = tmp_path / "data"
    assert cli.main(["dataset", "suite", "--runs", str(tmp_path / "runs"), "--games", "Flak", "--kinds", "random",
                     "--steps", "40", "--envs", "4", "--no-progress", "--data-path", str(data)]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert re.match(r"wrote octax/Flak/random-v0: \d+ episodes \(\d+ whole: mean return (\S+)\), 40 steps, ", line), line
    assert (data / "octax" / "Flak" / "random-v0" / "data" / "main_data.hdf5").is_file()
    # medium and expert need the game's training run: the error names the command that makes it
    assert cli.main(["dataset", "suite", "--runs", str(tmp_path / "runs"), "--games", "Flak", "--kinds", "expert",
                     "--steps", "40", "--no-progress", "--data-path", str(data)]) == 1
    assert "octax-gym train ppo --games Flak --save-at-evals" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        cli.main(["dataset", "suite", "--games", "Flak"])  # --runs is required
    assert cli.main(["dataset", "suite", "--runs", str(tmp_path), "--games", "Pong", "--no-progress"]) == 1
    assert "Airplane" in capsys.readouterr().err  # the suite's games listed
