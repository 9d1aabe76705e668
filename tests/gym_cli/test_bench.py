"""benchmarks/throughput.py and its door `octax-gym bench`: tiny runs, real output.

Each run compiles a rollout, so N and the step counts are as small as they go: these check the
plumbing and the output format, never a speed. The door runs the script's `main` in a child
process (its output read from the file descriptors, capfd): a child's JAX start-up each, so the
door itself is run a few times, and what the script prints and refuses is checked by calling the
`main` the child calls, in this process (`door_main`).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import jax
import pytest

from octax_gym import cli

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "benchmarks"))
import harness  # noqa: E402  (benchmarks/ is a folder of scripts, not a package)
import throughput  # noqa: E402

TINY = ["--envs", "2", "--steps", "2", "--repeats", "1"]
FIELDS = ["mode", "n", "devices", "steps", "sps", "ips", "state_bytes", "compile_s", "octax_sps",
          "octax_compile_s", "ratio", "device"]


def door_main(argv: list[str]) -> int:
    """What `octax-gym bench ARGV` runs in its child process, run here."""
    return throughput.main(argv, prog="octax-gym bench", progress=True)


def bench_lines(out: str) -> list[dict[str, str]]:
    """Each `BENCH throughput k=v ...` line of `out` as an ordered dict of strings."""
    return harness.parse_bench_lines(out, "throughput")


# The scripts' refusals, run as `python benchmarks/SCRIPT ARGS` runs them (the script as __main__,
# benchmarks/ first on sys.path, sys.exit's code), several in one subprocess: each refusal comes
# before any compile, so one JAX import serves them all. A real `python benchmarks/throughput.py`
# run is test_thin_script_still_runs_without_a_progress_bar's.
_REFUSALS = """
import contextlib, io, json, runpy, sys
sys.path.insert(0, 'benchmarks')
for script, argv in json.loads(sys.argv[1]):
    sys.argv, err = [script, *argv], io.StringIO()
    with contextlib.redirect_stderr(err):
        try:
            runpy.run_path(script, run_name='__main__')
            code = 0
        except SystemExit as exit:
            code = exit.code
    print(json.dumps([code, err.getvalue()]), flush=True)
"""


def script_refusals(cases: list[tuple[str, list[str]]]) -> list[tuple[int, str]]:
    """(return code, stderr) of each `python benchmarks/SCRIPT ARGV` in `cases`, from one subprocess."""
    result = subprocess.run([sys.executable, "-c", _REFUSALS, json.dumps(cases)],
                            capture_output=True, text=True, timeout=300, cwd=REPO, check=False)
    assert result.returncode == 0, result.stderr
    outcomes = [tuple(json.loads(line)) for line in result.stdout.splitlines()]
    assert len(outcomes) == len(cases), result.stdout
    return outcomes


def check_line(fields: dict[str, str], mode: str, n: int, steps: int) -> None:
    assert (fields["mode"], fields["n"], fields["steps"]) == (mode, str(n), str(steps))
    assert int(fields["sps"]) > 0 and int(fields["ips"]) == pytest.approx(int(fields["sps"]) * 44, rel=0.01)
    assert int(fields["state_bytes"]) > 4096
    assert float(fields["compile_s"]) >= 0  # gym: 0.0 when this process already compiled that N
    assert fields["device"] == jax.default_backend()


@pytest.mark.parametrize("mode", ["machine", "env", "gym"])
def test_bench_prints_one_parseable_line_per_n_and_the_bar_on_stderr(mode, octax_rom_dir, capsys):
    assert door_main(["--quick", "--no-octax", "--mode", mode, *TINY]) == 0
    out, err = capsys.readouterr()
    (fields,) = bench_lines(out)  # explicit --envs and --repeats win over --quick
    check_line(fields, mode, 2, 2)
    assert list(fields) == FIELDS + (["backend"] if mode == "gym" else [])
    assert (fields["octax_sps"], fields["octax_compile_s"], fields["ratio"], fields["devices"]) == ("na",) * 3 + ("1",)
    assert "run 1/1" in err and "BENCH" not in err  # the progress bar, on stderr only
    assert "run 1/1" not in out


def test_the_door_runs_the_script_with_its_bar_in_a_child(octax_rom_dir, capfd):
    assert cli.main(["bench", "--quick", "--no-octax", "--mode", "machine", *TINY]) == 0
    out, err = capfd.readouterr()
    (fields,) = bench_lines(out)
    check_line(fields, "machine", 2, 2)
    assert "run 1/1" in err and "BENCH" not in err and "run 1/1" not in out


@pytest.mark.parametrize("backend", ["jax", "torch"])
def test_gym_mode_backends(backend, capsys):
    assert door_main(["--no-octax", "--mode", "gym", "--backend", backend, "--no-progress", *TINY]) == 0
    out, err = capsys.readouterr()
    (fields,) = bench_lines(out)
    check_line(fields, "gym", 2, 2)
    assert fields["backend"] == backend and err == ""
    assert f"gym-{backend} n=2:" in out


def test_octax_comparison_and_jsonl(tmp_path, capsys):
    jsonl = tmp_path / "bench.jsonl"
    # N = 1 and 2: Pong steps other tests compile too (test_video's single env, TINY's and test_demo's 2)
    argv = ["--mode", "gym", "--envs", "1,2", "--steps", "2", "--repeats", "1", "--octax-max-envs", "1",
            "--jsonl", str(jsonl), "--no-progress"]
    assert door_main(argv) == 0
    lines = bench_lines(capsys.readouterr().out)
    assert [line["n"] for line in lines] == ["1", "2"]
    assert int(lines[0]["octax_sps"]) > 0 and float(lines[0]["ratio"]) > 0  # same work: 44 instructions a step
    assert lines[1]["octax_sps"] == "na"  # above --octax-max-envs
    records = [json.loads(line) for line in jsonl.read_text().splitlines()]
    assert [{k: ("na" if v is None else str(v)) for k, v in r.items()} for r in records] == lines


def test_missing_octax_is_a_one_line_note_not_a_crash(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "octax", None)  # `import octax` now raises ImportError
    assert door_main(["--mode", "machine", "--no-progress", *TINY]) == 0
    out = capsys.readouterr().out
    notes = [line for line in out.splitlines() if "octax comparison skipped" in line]
    assert len(notes) == 1 and "pip install 'octax-gym[dev]'" in notes[0]
    (fields,) = bench_lines(out)
    assert fields["octax_sps"] == "na" and fields["ratio"] == "na"


def _checked(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    throughput.add_arguments(parser)
    return throughput.check_args(parser, parser.parse_args(argv))


def test_quick_fills_only_what_is_not_given():
    assert (_checked(["--quick"]).envs, _checked(["--quick"]).repeats) == ([64, 512], 2)
    assert (_checked([]).envs, _checked([]).repeats) == ([1, 64, 512, 2048, 8192], 5)
    quick = _checked(["--quick", "--envs", "8,16", "--repeats", "3"])
    assert (quick.envs, quick.repeats) == ([8, 16], 3)
    assert _checked(["--mode", "gym"]).backend == "numpy" and _checked([]).backend is None
    assert _checked([]).progress is False


@pytest.mark.parametrize("argv, message", [
    (["--mode", "machine", "--backend", "torch"], "--backend applies to --mode gym only"),
    (["--mode", "gym", "--devices", "2"], "--devices must be 1"),
    (["--envs", "2,x"], "--envs must be"),
    (["--envs", "0"], "--envs must be"),
    (["--steps", "0"], "must be >= 1"),
    (["--key", "16"], "--key must be in -1..15"),
    (["--mode", "atari"], "invalid choice"),
])
def test_bad_options_are_usage_errors(argv, message, capsys):
    with pytest.raises(SystemExit) as exc:
        door_main(argv)
    assert exc.value.code == 2 and message in capsys.readouterr().err


def test_the_door_passes_on_a_usage_error_under_its_own_name(capfd):
    assert cli.main(["bench", "--key", "16"]) == 2
    assert "octax-gym bench: error: --key must be in -1..15, got 16" in capfd.readouterr().err


def test_a_key_pong_has_no_action_for_fails_before_compiling(capsys):
    assert door_main(["--mode", "env", "--key", "5", *TINY]) == 1
    err = capsys.readouterr().err
    assert "octax-gym bench: error: Pong has no action for key 5 (keys [1, 4])" in err


def test_a_missing_rom_is_an_error(tmp_path, capsys):
    assert door_main(["--rom", str(tmp_path / "nothing.ch8"), *TINY]) == 1
    assert "octax-gym bench: error:" in capsys.readouterr().err


def test_devices_split_the_batch_although_this_process_has_computed(capfd):
    # The script's JAX is its child process's own: `--devices` works even after this process (which
    # imported octax_gym, and jax with it) has fixed its own device count by computing.
    jax.numpy.zeros(1).block_until_ready()
    assert cli.main(["bench", "--devices", "2", "--envs", "4", "--steps", "2", "--repeats", "1", "--no-octax",
                     "--no-progress"]) == 0
    out = capfd.readouterr().out
    (fields,) = bench_lines(out)
    assert fields["devices"] == "2" and fields["mode"] == "machine"
    assert "devices=2" in out.splitlines()[0]


def test_thin_script_still_runs_without_a_progress_bar():
    result = subprocess.run([sys.executable, "benchmarks/throughput.py", "--no-octax", *TINY],
                            capture_output=True, text=True, timeout=300, cwd=REPO, check=False)
    assert result.returncode == 0, result.stderr
    (fields,) = bench_lines(result.stdout)
    check_line(fields, "machine", 2, 2)
    assert list(fields) == FIELDS and "run 1/1" not in result.stderr
    assert result.stdout.startswith("# jax ")


def test_the_scripts_report_usage_errors(tmp_path):
    (throughput_usage, env_loop_usage, platforms_usage, no_programs, not_chip8) = script_refusals([
        ("benchmarks/throughput.py", ["--backend", "torch"]),
        ("benchmarks/env_loop.py", ["--layers", "atari"]),
        ("benchmarks/platforms.py", ["--platforms", "nes"]),
        ("benchmarks/platforms.py", ["--platforms", "schip", "--archive", str(tmp_path)]),
        ("benchmarks/platforms.py", ["--same-program", "--archive-chip8-game", "civiliz8n"])])
    code, err = throughput_usage
    assert code == 2 and "--backend applies to --mode gym only" in err
    code, err = env_loop_usage
    assert code == 2 and "--layers takes env, gym" in err
    code, err = platforms_usage
    assert code == 2 and "unknown platform(s) ['nes']; valid: chip8, schip, xochip" in err
    code, err = no_programs
    assert code == 1 and "programs.json" in err
    code, err = not_chip8
    assert code == 1 and "'civiliz8n' is not a CHIP-8 program of the archive" in err


def test_the_door_names_what_a_wheel_install_lacks(monkeypatch, tmp_path, capsys):
    from octax_gym.cli import bench as cli_bench

    monkeypatch.setattr(cli_bench, "BENCHMARKS", tmp_path / "benchmarks")  # as beside an installed wheel
    assert cli.main(["bench", "--quick"]) == 1
    err = capsys.readouterr().err
    assert "benchmarks/throughput.py of a source checkout" in err and "make bench" in err


def test_only_bench_takes_arguments_it_does_not_declare(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["list", "--envs", "2"])
    assert exc.value.code == 2 and "unrecognized arguments: --envs 2" in capsys.readouterr().err


@pytest.mark.slow  # a long check (>20 s on 2 cores); CI's test-slow runs it
def test_env_loop_prints_one_line_per_case_against_the_machine_and_octax():
    result = subprocess.run(
        [sys.executable, "benchmarks/env_loop.py", "--envs", "2", "--steps", "2", "--repeats", "1",
         "--noop-max", "0,3", "--layers", "env,gym", "--max-episode-steps", "1"],
        capture_output=True, text=True, timeout=300, cwd=REPO, check=False)
    assert result.returncode == 0, result.stderr
    lines = harness.parse_bench_lines(result.stdout, "env_loop")
    assert [(line["layer"], line["noop_max"]) for line in lines] == [("env", "0"), ("env", "3"), ("gym", "0"), ("gym", "3")]
    for line in lines:
        assert (line["autoreset"], line["sticky"], line["max_episode_steps"]) == ("1", "0.25", "1")
        # vs_machine comes from the unrounded rates; the line's rates are rounded to integers, which
        # at these tiny runs moves their ratio by up to half a unit of each.
        sps, machine_sps = int(line["sps"]), int(line["machine_sps"])
        low, high = (sps - 0.5) / (machine_sps + 0.5), (sps + 0.5) / max(machine_sps - 0.5, 0.5)
        assert low - 0.0005 <= float(line["vs_machine"]) <= high + 0.0005, line
        assert int(line["octax_sps"]) > 0 and float(line["ratio"]) > 0


@pytest.mark.slow  # three platforms' compiles (17 s); the same-program run below covers chip8 and schip in make test
def test_platforms_prints_one_line_per_platform_with_its_state_bytes(octax_rom_dir):
    result = subprocess.run(
        [sys.executable, "benchmarks/platforms.py", "--envs", "2", "--steps", "2", "--repeats", "1"],
        capture_output=True, text=True, timeout=300, cwd=REPO, check=False)
    assert result.returncode == 0, result.stderr
    lines = harness.parse_bench_lines(result.stdout, "platforms")
    assert [(line["platform"], line["game"]) for line in lines] == [
        ("chip8", "Pong"), ("schip", "blackrainbow"), ("xochip", "civiliz8n")]
    assert [int(line["state_bytes"]) for line in lines] == [4508, 5584, 68304]
    for line in lines:
        assert int(line["ips"]) == pytest.approx(int(line["sps"]) * 4 * int(line["instructions_per_frame"]), rel=0.01)
    assert float(lines[0]["ratio"]) > 0 and lines[1]["ratio"] == "na"


def test_platforms_same_program_runs_one_chip8_program_on_every_platform(octax_rom_dir):
    """Each program on chip8 and one later platform (`--platforms`, which the script loops over
    alike: each is one more compile, XO-CHIP's the dearest); every platform's own program and
    state: the slow test above."""
    result = subprocess.run(
        [sys.executable, "benchmarks/platforms.py", "--same-program", "--platforms", "chip8,schip", "--envs", "2",
         "--steps", "2", "--repeats", "1"],
        capture_output=True, text=True, timeout=300, cwd=REPO, check=False)
    assert result.returncode == 0, result.stderr
    lines = harness.parse_bench_lines(result.stdout, "same_program")
    assert [(line["program"], line["platform"]) for line in lines] == [
        (program, platform) for program in ("Pong", "carbon8") for platform in ("chip8", "schip")]
    assert [int(line["instructions_per_frame"]) for line in lines] == [11] * 2 + [15] * 2
    for chip8, *later in (lines[:2], lines[2:]):
        assert float(chip8["ratio"]) == 1.0
        for line in later:  # the ratio is the platform's instructions/s over chip8's
            assert float(line["ratio"]) == pytest.approx(int(line["ips"]) / int(chip8["ips"]), abs=0.002)
    # its refusal of a game that is not CHIP-8: test_the_scripts_report_usage_errors


@pytest.mark.slow  # compiles a PPO update (about 10 s)
def test_train_throughput_counts_the_network_flops_per_step(octax_rom_dir):
    result = subprocess.run(
        [sys.executable, "benchmarks/train_throughput.py", "--games", "Airplane", "--num-envs", "8",
         "--num-minibatches", "2", "--updates", "1", "--matmul-size", "256"],
        capture_output=True, text=True, timeout=600, cwd=REPO, check=False)
    assert result.returncode == 0, result.stderr
    line, = harness.parse_bench_lines(result.stdout, "train_throughput")
    assert line["algo"] == "ppo" and line["agents"] == "1" and line["envs"] == "8"
    # the paper's network: a forward pass to act and 4 gradients (about 3 passes each) a step,
    # some 6 MFLOP a pass (3.2M multiply-adds), so tens of MFLOP, not the loop-undercounted few
    assert 40 < float(line["mflop_per_step"]) < 150
    assert 0 < float(line["fraction"]) and int(line["sps"]) > 0
    assert float(line["gflops"]) == pytest.approx(float(line["mflop_per_step"]) * int(line["sps"]) / 1e3, rel=0.01)
