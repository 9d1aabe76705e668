"""`octax-gym roms list|install|import` (octax_gym/cli/roms.py), over fake games and the real registry."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from fake_games import make_spec

from octax_core.env import romstore
from octax_core.env.games import list_games
from octax_gym import cli
from octax_gym.cli import roms as cli_roms

PONG, BRIX = b"\x00\xe0pong", b"\x00\xe0brix"
PROJECT_ROM_DIR = romstore.PROJECT_ROM_DIR  # our own games' ROMs (roms/), hidden by `store`


@pytest.fixture(autouse=True)
def store(tmp_path, monkeypatch):
    monkeypatch.setenv("OCTAX_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.delenv("OCTAX_ROM_DIR", raising=False)
    monkeypatch.setattr(romstore, "PROJECT_ROM_DIR", tmp_path / "no-project-roms")
    return tmp_path


@pytest.fixture
def fake_games(monkeypatch):
    specs = [make_spec("Brix", "Brix.ch8", BRIX), make_spec("Pong", "Pong (1 player).ch8", PONG)]
    monkeypatch.setattr(cli_roms, "game_specs", lambda two_player_only=False: specs)
    return specs


def test_roms_list_shows_each_game_present_or_not(tmp_path, capsys, fake_games):
    user = romstore.user_rom_dir()
    user.mkdir(parents=True)
    (user / "Pong (1 player).ch8").write_bytes(PONG)
    assert cli.main(["roms", "list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["game", "rom", "file", "present", "verified", "path"]
    assert lines[1].split() == ["Brix", "Brix.ch8", "missing", "-", "-"]
    assert lines[2].split()[:7] == ["Pong", "Pong", "(1", "player).ch8", "yes", "yes", str(user / "Pong")]
    assert lines[2].endswith(str(user / "Pong (1 player).ch8"))
    assert "1/2 ROMs present and verified" in lines[4] and str(user) in lines[4]
    assert "octax-gym roms install" in lines[5]


def test_roms_list_flags_a_wrong_hash(capsys, fake_games):
    user = romstore.user_rom_dir()
    user.mkdir(parents=True)
    (user / "Brix.ch8").write_bytes(b"tampered")
    cli.main(["roms", "list"])
    brix_line = capsys.readouterr().out.splitlines()[1]
    assert "yes" in brix_line and "NO: sha1 " + romstore.sha1_hex(b"tampered") in brix_line


def test_roms_import_a_wheel_then_list_is_all_verified(tmp_path, capsys, fake_games):
    wheel = tmp_path / "octax-0.1.1-py3-none-any.whl"
    with zipfile.ZipFile(wheel, "w") as zf:
        zf.writestr("octax/roms/x.ch8", PONG)
        zf.writestr("roms/y.ch8", BRIX)
    assert cli.main(["roms", "import", str(wheel)]) == 0
    out = capsys.readouterr().out
    assert "installed  Brix.ch8  (Brix)" in out and "every game has its ROM" in out
    cli.main(["roms", "list"])
    assert "2/2 ROMs present and verified" in capsys.readouterr().out


def test_roms_import_to_dest_names_what_is_still_missing(tmp_path, capsys, fake_games):
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "a.bin").write_bytes(PONG)
    assert cli.main(["roms", "import", str(tmp_path / "src"), "--dest", str(tmp_path / "d")]) == 0
    out = capsys.readouterr().out
    assert "no matching ROM for: Brix" in out and "is not searched; add it to OCTAX_ROM_DIR" in out
    assert (tmp_path / "d" / "Pong (1 player).ch8").read_bytes() == PONG


def test_roms_import_fails_when_nothing_matches(tmp_path, capsys, fake_games):
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "Brix.ch8").write_bytes(b"not brix")
    assert cli.main(["roms", "import", str(tmp_path / "src")]) == 1
    assert "no file there has the SHA-1" in capsys.readouterr().err
    assert cli.main(["roms", "import", str(tmp_path / "missing")]) == 1
    assert "octax-gym: error: nothing to import" in capsys.readouterr().err


def test_roms_install_calls_the_store_with_the_pinned_version(tmp_path, capsys, monkeypatch, fake_games):
    calls = []
    monkeypatch.setattr(romstore, "install_from_pypi", lambda *a: calls.append(a) or [])
    assert cli.main(["roms", "install", "--dest", str(tmp_path / "d")]) == 1  # nothing came back
    assert calls == [(fake_games, tmp_path / "d", "0.1.1")]

    def fail(*a):
        raise romstore.RomInstallError("pip download failed (exit 1)")
    monkeypatch.setattr(romstore, "install_from_pypi", fail)
    assert cli.main(["roms", "install"]) == 1
    assert "octax-gym: error: pip download failed" in capsys.readouterr().err


def test_usage_errors_exit_2(capsys):
    assert cli.main([]) == 2
    assert cli.main(["roms"]) == 2
    with pytest.raises(SystemExit) as exit_:
        cli.main(["roms", "bogus"])
    assert exit_.value.code == 2


def test_python_dash_m_runs_the_cli():
    proc = subprocess.run([sys.executable, "-m", "octax_gym", "roms", "--help"],
                          check=False, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and "import" in proc.stdout and "install" in proc.stdout


@pytest.mark.skipif(not list_games(), reason="no games registered yet")
def test_roms_list_with_the_real_registry_and_shared_roms(octax_rom_dir, capsys, monkeypatch):
    monkeypatch.setenv("OCTAX_ROM_DIR", str(octax_rom_dir))
    monkeypatch.setattr(romstore, "PROJECT_ROM_DIR", PROJECT_ROM_DIR)
    assert cli.main(["roms", "list"]) == 0
    n = len(set(list_games()) | set(list_games(players=2)))  # the two-player-only games' ROMs too
    assert f"{n}/{n} ROMs present and verified" in capsys.readouterr().out


def test_install_does_not_count_our_own_games_as_missing(tmp_path, capsys, monkeypatch, fake_games):
    """Our own games' ROMs are built in roms/, never in the octax wheel: found there, not missing."""
    own_rom = b"\x12\x00own game"
    own = make_spec("Own", "own.ch8", own_rom)
    project = tmp_path / "project-roms"
    project.mkdir()
    (project / "own.ch8").write_bytes(own_rom)
    monkeypatch.setattr(romstore, "PROJECT_ROM_DIR", project)
    monkeypatch.setattr(cli_roms, "game_specs", lambda two_player_only=False: [*fake_games, own])

    def wheel_of_two(specs, dest, version):
        target = romstore.user_rom_dir()
        return romstore.import_roms(_folder_with(tmp_path / "wheel", {"a.ch8": BRIX, "b.ch8": PONG}), specs, target)
    monkeypatch.setattr(romstore, "install_from_pypi", wheel_of_two)
    assert cli.main(["roms", "install"]) == 0
    out = capsys.readouterr().out
    assert "every game has its ROM" in out and "Own" not in out


def test_install_if_missing_downloads_only_when_a_rom_is_missing(tmp_path, capsys, monkeypatch, fake_games):
    calls = []

    def wheel(specs, dest, version):
        calls.append(version)
        return romstore.import_roms(_folder_with(tmp_path / "wheel", {"a.ch8": BRIX, "b.ch8": PONG}), specs, dest)
    monkeypatch.setattr(romstore, "install_from_pypi", wheel)
    assert cli.main(["roms", "install", "--if-missing"]) == 0
    out = capsys.readouterr().out
    assert calls == ["0.1.1"] and "2 game(s) without a verified ROM: Brix, Pong" in out
    assert cli.main(["roms", "install", "--if-missing"]) == 0
    assert calls == ["0.1.1"]  # all there now: no second download
    assert "every game (2) has its verified ROM already; nothing to download" in capsys.readouterr().out


def _folder_with(folder: Path, files: dict) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in files.items():
        (folder / name).write_bytes(data)
    return folder


def test_the_rom_commands_cover_the_two_player_only_games():
    """Paddles (octax suite) is played by two only: `roms install` must still fetch its ROM."""
    from octax_gym.cli.common import game_specs

    ids = {spec.id for spec in game_specs(two_player_only=True)}
    assert {"Paddles", "TankArchive", "UltimateTicTacToe"} <= ids
    assert "Paddles" not in {spec.id for spec in game_specs()}
