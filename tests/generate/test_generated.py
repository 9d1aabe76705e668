"""`octax_gym.generated.load_archive`: an archive's games as GameSpecs for make_mix and Mix-v0."""

import subprocess
import sys
from pathlib import Path

import gymnasium
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
import octax_gym  # noqa: F401  (registers octax/Mix-v0)
from octax_core.generate import filters, rounds
from octax_core.generate.families import get_family
from octax_gym.cli.generate import write_round
from octax_gym.generated import load_archive

COUNT = 6
REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A dodger archive of 6 variants, half of them rejected (the checks faked: their verdicts
    are not what is tested here)."""
    folder = tmp_path_factory.mktemp("archive")
    candidates = rounds.family_candidates(get_family("dodger"), COUNT, 0)

    def fake_check(specs, roms, settings):
        return [filters.Verdict(() if i % 2 == 0 else ("made up",), 1.0, 0.5, 3.0) for i in range(len(specs))]
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(filters, "check", fake_check)
        write_round(folder, candidates, filters.Settings(), {"family": "dodger"})
    return folder


def test_splits_follow_the_held_out_range(folder):
    train, test = load_archive(folder, "train"), load_archive(folder, "test")
    every = load_archive(folder)
    assert {s.id for s in train} | {s.id for s in test} == {s.id for s in every}
    assert len(every) == COUNT // 2  # the rejected are left out
    assert len(load_archive(folder, accepted_only=False)) == COUNT
    params = {row.name: row.params for row in rounds.family_candidates(get_family("dodger"), COUNT, 0)}
    assert all(params[s.id]["fall"] == 3 for s in test) and all(params[s.id]["fall"] != 3 for s in train)


def test_bad_splits_are_named(folder, tmp_path):
    with pytest.raises(ValueError, match="unknown split 'validation'; valid: train, test"):
        load_archive(folder, "validation")
    with pytest.raises(ValueError, match="no archive at"):
        load_archive(tmp_path)


def test_the_variants_are_data_in_one_mix(folder):
    specs = load_archive(folder, accepted_only=False)
    # one score, end and lives function for the whole family, one quirks profile and one speed:
    # what differs per variant is its ROM, held in each env's memory
    assert len({(s.score_fn, s.terminated_fn, s.lives_fn) for s in specs}) == 1
    env, params = octax_core.make_mix(specs)
    assert len(set(env.machine.profiles)) == 1
    games = jnp.arange(8) % len(specs)
    _, states = jax.vmap(lambda k, g: env.reset(k, params, game=g))(jax.random.split(jax.random.key(0), 8), games)
    step = jax.jit(jax.vmap(env.step, in_axes=(0, 0, 0, None)))
    for _ in range(40):
        _, states, *_ = step(jax.random.split(jax.random.key(1), 8), states, jnp.full(8, 2), params)
    screens = np.asarray(states.machine.screen)
    assert len({screens[i].tobytes() for i in range(len(specs))}) == len(specs)  # each env its own program


def test_gymnasium_mix_takes_the_specs(folder):
    specs = load_archive(folder, "train")
    envs = gymnasium.make_vec("octax/Mix-v0", num_envs=4, games=specs)
    try:
        _, info = envs.reset(seed=0)
        *_, info = envs.step(np.zeros(4, np.int64))
        assert set(np.asarray(info["game"]).tolist()) <= set(range(len(specs)))
        assert envs.unwrapped.core_env.games == tuple(s.id for s in specs)
    finally:
        envs.close()


@pytest.mark.slow  # a subprocess that compiles two mixes (>20 s on 2 cores); CI's test-slow runs it
def test_benchmark_prints_its_line(folder):
    sys.path.insert(0, str(REPO / "benchmarks"))
    import harness  # benchmarks/ is a folder of scripts, not a package

    result = subprocess.run([sys.executable, "benchmarks/generated_mix.py", "--archive", str(folder),
                             "--include-rejected", "--envs", "4", "--steps", "2", "--repeats", "1"],
                            capture_output=True, text=True, timeout=600, cwd=REPO, check=False)
    assert result.returncode == 0, result.stderr
    line, = harness.parse_bench_lines(result.stdout, "generated_mix")
    assert line["variants"] == str(COUNT) and line["n"] == "4"
    assert abs(float(line["speed_ratio"]) - int(line["all_sps"]) / int(line["one_sps"])) < 0.01
    assert line["met"] in ("0", "1")
