"""The trainer's settings: the presets hold the paper's numbers, `--games octax16` is the paper's 16
(one list, octax_core's), and every bad flag is refused with a message naming it, before any JAX
work (exit status 1, "octax-gym: error: ...")."""

from __future__ import annotations

import dataclasses

import pytest

pytest.importorskip("flax")
from octax_core.env.mix import MIXES  # noqa: E402
from octax_gym.cli import main  # noqa: E402
from octax_gym.train import TrainConfig, preset, resolve_games  # noqa: E402


def test_the_paper_preset_is_the_papers_setup():
    ppo = preset("paper", "ppo")
    assert (ppo.num_envs, ppo.num_steps, ppo.update_epochs, ppo.num_minibatches) == (512, 32, 4, 32)
    assert (ppo.learning_rate, ppo.clip_eps, ppo.gae_lambda, ppo.ent_coef, ppo.vf_coef, ppo.max_grad_norm) == \
        (5e-4, 0.2, 0.95, 0.01, 0.5, 0.5)
    assert ppo.total_steps == 5_000_000 and not ppo.anneal_lr
    pqn = preset("paper", "pqn")
    assert (pqn.num_envs, pqn.num_steps, pqn.num_minibatches, pqn.q_lambda, pqn.max_grad_norm) == (512, 32, 32, 0.9, 10.0)
    assert (pqn.epsilon_start, pqn.epsilon_finish, pqn.epsilon_fraction) == (1.0, 0.05, 0.1)
    cpu = preset("cpu", "ppo")
    assert (cpu.num_envs, cpu.num_minibatches, cpu.clip_eps) == (64, 8, 0.2)  # smaller batch, same algorithm


def test_a_flag_overrides_its_preset_value():
    assert preset("paper", "ppo", num_envs=64, num_minibatches=8).num_envs == 64


def test_the_network_layout_is_a_flag_of_every_algorithm():
    from octax_gym.cli import build_parser
    from octax_gym.cli.train import config_from_args

    for algorithm, game in (("ppo", "Brix"), ("pqn", "Brix"), ("multitask", "Brix,Pong"), ("selfplay", "Cycles")):
        args = build_parser().parse_args(["train", algorithm, "--games", game, "--network-layout", "paper"])
        assert config_from_args(args).network_layout == "paper"
    assert config_from_args(build_parser().parse_args(["train", "ppo"])).network_layout == "image"


def test_octax16_is_the_cores_list_of_the_papers_games():
    assert resolve_games("octax16") == MIXES["octax16"] and len(MIXES["octax16"]) == 16
    assert resolve_games("airplane,octax/Deep8-v0") == ("Airplane", "Deep8")


@pytest.mark.parametrize("flags, message", [
    (["--games", "Airplan"], "unknown game 'Airplan' (did you mean 'Airplane'?)"),
    (["--num-minibatches", "7"], "not divisible by num_minibatches = 7"),
    (["--num-seeds", "0"], "num_seeds must be an int >= 1, got 0"),
    (["--total-steps", "100"], "total_steps = 100 is less than one update"),
    (["--preset", "gpu"], "preset must be one of paper, cpu, got 'gpu'"),
    (["--devices", "some"], "devices must be one of '', 'all', got 'some'"),
    (["--gamma", "1.5"], "gamma must be in [0, 1], got 1.5"),
    (["--learning-rate", "0"], "learning_rate must be > 0, got 0.0"),
    (["--q-lambda", "0.5"], "--q-lambda: not a setting of ppo (of pqn)"),
    (["--no-game-input"], "--game-input: not a setting of ppo (of multitask)"),
    (["--games", "Airplane,Airplane"], "games names a game twice"),
    (["--games", "Airplane,BlackRainbow"], "a mix runs games of one platform"),
    (["--resume", "/nonexistent", "--seed", "2"], "--resume takes the run's own settings"),
    (["--resume", "/nonexistent"], "no config.json in /nonexistent"),
    (["--dataset", "octax/Flak/expert-v0"], "--dataset: not a setting of ppo (of bc and cql)"),
])
def test_bad_flags_are_refused_by_name(flags, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # a refused run must write nothing, not even its default runs/ folder
    assert main(["train", "ppo", *flags, "--no-progress"]) == 1
    assert message in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_offline_training_needs_a_dataset(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["train", "bc", "--no-progress"]) == 1
    assert "bc trains on a dataset: give its Minari id (--dataset" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_an_unknown_algorithm_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["train", "a2c"])
    assert exit_.value.code == 2 and "invalid choice: 'a2c'" in capsys.readouterr().err


def test_check_names_the_setting():
    with pytest.raises(ValueError, match="agent_map must be one of"):
        dataclasses.replace(TrainConfig(), agent_map="pmap").check()
    with pytest.raises(ValueError, match="network_layout must be one of 'image', 'paper', got 'columns'"):
        dataclasses.replace(TrainConfig(), network_layout="columns").check()
    with pytest.raises(ValueError, match="env override must be one of"):
        dataclasses.replace(TrainConfig(), env_overrides=(("obs_scale", 255),)).check()
