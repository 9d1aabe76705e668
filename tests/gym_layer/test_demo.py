"""`python -m octax_gym.demo`: the games table, the timed random agent and the video, with tiny sizes.

The timed run and the video both use 2 envs here, so they share one compiled Pong program.
"""

from __future__ import annotations

import contextlib
import io
import re
import subprocess
import sys

import cv2
import pytest

import octax_gym
from octax_core.env import romstore
from octax_gym import demo


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory):
    """Runs the demo once: (exit status, stdout, the video path)."""
    out = tmp_path_factory.mktemp("demo") / "demo-pong.mp4"
    stdout = io.StringIO()  # capsys is function-scoped, so a module fixture captures by hand
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(io.StringIO()):
        status = demo.main(["--steps", "5", "--envs", "2", "--video-steps", "3", "--out", str(out)])
    return status, stdout.getvalue(), out


def test_demo_prints_every_game_with_its_rom(demo_run):
    status, text, _ = demo_run
    assert status == 0
    rows = {line.split()[0]: line.split()[1:] for line in text.splitlines() if line.startswith("octax/")}
    assert sorted(rows) == sorted(octax_gym.ENV_IDS)
    assert rows["octax/Pong-v0"] == ["timing", "3", "yes"]  # no-op, up, down
    assert f"{len(octax_gym.ENV_IDS)} envs, {len(octax_gym.ENV_IDS)} with their ROM." in text


def test_demo_times_the_steps_after_the_compiling_one(demo_run):
    _, text, _ = demo_run
    match = re.search(r"^([\d,]+) env steps in ([\d.]+) s: ([\d,]+) steps/s", text, re.MULTILINE)
    assert match, text
    assert int(match.group(1).replace(",", "")) == 2 * 4  # 2 envs x (5 steps - the first)
    assert float(match.group(3).replace(",", "")) > 0
    assert re.search(r"^compile \(reset \+ first step\): [\d.]+ s", text, re.MULTILINE)
    assert "no episode ended yet" in text  # 5 steps: Pong waits 24 steps before its first serve


def test_demo_writes_its_video(demo_run):
    _, text, out = demo_run
    assert f"video: {out.resolve()}" in text and "4 frames, 1026x256 at 15 fps" in text
    capture = cv2.VideoCapture(str(out))
    frames = 0
    while capture.read()[0]:
        frames += 1
    assert frames == 4  # the first screen + 3 steps
    assert (capture.get(cv2.CAP_PROP_FRAME_WIDTH), capture.get(cv2.CAP_PROP_FRAME_HEIGHT)) == (1026, 256)


def test_print_games_marks_missing_roms(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("OCTAX_ROM_DIR", str(tmp_path / "none"))
    monkeypatch.setenv("OCTAX_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setattr(romstore, "PROJECT_ROM_DIR", tmp_path / "no-project-roms")
    demo.print_games()
    text = capsys.readouterr().out
    assert re.search(r"^octax/Pong-v0\s+timing\s+3\s+missing$", text, re.MULTILINE)
    assert "0 with their ROM. To get the missing ones: run `octax-gym roms install`" in text


def test_demo_reports_errors_with_exit_status_1(monkeypatch, capsys):
    # The ROM lookup sits behind a per-process program cache, so the missing ROM is simulated here.
    def no_rom(*args, **kwargs):
        raise romstore.RomNotFoundError("no ROM file 'Pong (1 player).ch8' for game 'Pong'")

    monkeypatch.setattr(demo, "run_random_agent", no_rom)
    assert demo.main(["--steps", "2"]) == 1
    assert "octax_gym.demo: error: no ROM file 'Pong (1 player).ch8'" in capsys.readouterr().err


@pytest.mark.parametrize("args", [["--steps", "1"], ["--envs", "0"], ["--video-steps", "0"]])
def test_demo_rejects_too_small_sizes(args, capsys):
    with pytest.raises(SystemExit) as exit_info:
        demo.main(args)
    assert exit_info.value.code == 2
    assert "must be >= " in capsys.readouterr().err


def test_the_core_does_not_import_gymnasium():
    # The demo moved out of octax_core (it was octax_core.demo) because the core imports only JAX and numpy.
    code = ("import importlib, pkgutil, sys, octax_core\n"
            "for m in pkgutil.walk_packages(octax_core.__path__, 'octax_core.'): importlib.import_module(m.name)\n"
            "print(sorted(n for n in ('gymnasium', 'cv2', 'tqdm', 'octax_gym') if n in sys.modules))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[]"
