"""The `octax-gym` command line as a newcomer first runs it (issue 39): `--version`, a ROM file
where a game goes (`info`, `record`, `play`, as `trace` always took one), no JAX INFO lines from
`play`, and a quiet exit when the reader of the output goes away (`octax-gym roms list | head`).

The ROM file is tests/counter_game.py's Counter, played as a bare ROM: 16 keys, no reward.
"""

from __future__ import annotations

import io
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import octax_gym
from octax_gym import cli

REPO = Path(__file__).resolve().parents[2]


def test_version_prints_the_package_version(capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["--version"])
    assert exit_info.value.code == 0
    assert capsys.readouterr().out == f"octax-gym {octax_gym.__version__}\n"


# --- a ROM file where a game goes -------------------------------------------------------------

@pytest.mark.parametrize("suffix, platform", [(".ch8", "chip8"), (".sc8", "schip"), (".xo8", "xochip")])
def test_info_describes_a_rom_file_by_its_ending(counter_rom, tmp_path, capsys, suffix, platform):
    rom = tmp_path / f"counter{suffix}"
    shutil.copy(counter_rom, rom)
    assert cli.main(["info", str(rom)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"counter{suffix}  (the ROM file {str(rom)!r})")
    assert "Discrete(17)" in out and "16  CHIP-8 key F" in out
    assert f"platform:          {platform}\n" in out and "no game spec" in out


def test_record_plays_a_rom_file_into_a_video(counter_rom, tmp_path, capsys):
    pytest.importorskip("imageio_ffmpeg")
    out = tmp_path / "counter.mp4"
    assert cli.main(["record", str(counter_rom), "--steps", "3", "--out", str(out), "--no-progress"]) == 0
    assert f"wrote {out}: 4 frames, 512x256" in capsys.readouterr().out and out.stat().st_size > 0


def test_play_serves_a_rom_file_with_its_16_keys(counter_rom, monkeypatch, capsys):
    pytest.importorskip("aiohttp")
    from octax_gym.play.server import PlayServer

    served = []

    def run(server, port=0, on_start=None):
        session = server.session
        served.append((session.spec.id, session.num_actions, session.seat_keys, session.obs.shape))

    monkeypatch.setattr(PlayServer, "run", run)
    assert cli.main(["play", str(counter_rom)]) == 0
    assert served == [("counter.ch8", 17, (tuple(range(16)),), (1, 4, 32, 64))]  # reset: the first screen


def test_play_refuses_to_record_a_rom_file(counter_rom, capsys):
    pytest.importorskip("aiohttp")
    assert cli.main(["play", str(counter_rom), "--record", "me/counter-v0"]) == 1
    assert "a ROM file with no game spec" in capsys.readouterr().err


def test_a_name_that_is_no_game_nor_file_says_both_are_taken(capsys):
    for command in (["info", "Pongg"], ["play", "Pongg"], ["record", "Pongg", "--steps", "1", "--out", "x.mp4"]):
        assert cli.main(command) == 1
        err = capsys.readouterr().err
        assert err.startswith("octax-gym: error: unknown game 'Pongg' (did you mean 'Pong'?)"), command
        assert "or the path of a ROM file (.ch8, .sc8, .xo8; there is no file 'Pongg')" in err, command


# --- play's log, and a closed pipe ----------------------------------------------------------------

def test_play_logs_its_own_lines_and_no_library_s_info(tmp_path):
    """In a fresh process (logging is set up once per process): a library's INFO record, as JAX's
    TPU probe logs on every start, stays silent; the server's own INFO lines are shown."""
    pytest.importorskip("aiohttp")
    script = textwrap.dedent("""
        import logging, sys
        from octax_gym.play import server, session
        class Server:
            def __init__(self, session, **kwargs):
                pass
            def run(self, port=0, on_start=None):
                logging.getLogger("jax._src.xla_bridge").info("Unable to initialize backend 'tpu'")
                logging.getLogger("octax_gym.play").info("served")
        server.PlayServer = Server
        session.Session = lambda *args, **kwargs: type("Session", (), {"close": lambda self: None})()
        from octax_gym.cli import main
        sys.exit(main(["play", "Brix"]))
    """)
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
                            cwd=tmp_path, check=False)
    assert result.returncode == 0, result.stderr
    assert "octax_gym.play INFO served" in result.stderr
    assert "tpu" not in result.stderr.lower(), result.stderr


def test_play_logs_to_the_stderr_of_each_run(monkeypatch):
    """The command run twice in one process (as tests and notebooks do): the second run's lines go
    to the second run's stderr, not to the first one's, which may be closed by then."""
    import logging

    from octax_gym.cli.play import _log_octax_gym

    logger = logging.getLogger("octax_gym")
    monkeypatch.setattr(logger, "handlers", [])
    first, second = io.StringIO(), io.StringIO()
    monkeypatch.setattr(sys, "stderr", first)
    _log_octax_gym()
    logging.getLogger("octax_gym.play").info("first run")
    first.close()
    monkeypatch.setattr(sys, "stderr", second)
    _log_octax_gym()
    logging.getLogger("octax_gym.play").info("second run")
    assert "octax_gym.play INFO second run" in second.getvalue()
    assert "Logging error" not in second.getvalue()
    assert len(logger.handlers) == 1


def test_a_closed_pipe_ends_the_command_quietly(monkeypatch, capsys):
    read, write = os.pipe()
    os.close(read)  # the reader is gone before the first line, as `| head` is after ten
    stdout = io.TextIOWrapper(io.FileIO(write, "w"), write_through=True)
    monkeypatch.setattr(sys, "stdout", stdout)
    try:
        assert cli.main(["roms", "list"]) == 1  # the status a SIGPIPE exit has; nothing printed
    finally:
        stdout.close()
    assert capsys.readouterr().err == ""
