"""`octax-gym list` and `octax-gym info` (octax_gym/cli/games.py), over the real registry and ROMs."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import pytest

from octax_core.env import environment as core_env
from octax_core.env import romstore
from octax_core.env.games import CATEGORIES, get_spec, list_games
from octax_gym import cli, env_id
from octax_gym.envs import game_names


@pytest.fixture
def no_roms(tmp_path, monkeypatch):
    """A ROM store with nothing in it."""
    monkeypatch.setenv("OCTAX_ROM_DIR", str(tmp_path / "empty"))
    monkeypatch.setenv("OCTAX_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setattr(romstore, "PROJECT_ROM_DIR", tmp_path / "no-project-roms")


def _rows(out: str) -> dict[str, list[str]]:
    """`list` table rows keyed by Gymnasium id, cells split on runs of 2+ spaces."""
    import re

    return {cells[0]: cells for line in out.splitlines()
            if (cells := re.split(r"\s{2,}", line.strip()))[0].startswith("octax/")}


def test_list_shows_every_game_with_category_actions_and_verified_rom(octax_rom_dir, capsys):
    assert cli.main(["list"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].split() == ["gymnasium", "id", "category", "actions", "(keys)", "rom", "title"]
    rows = _rows(out)
    assert list(rows) == [env_id(game) for game in list_games()]
    assert rows["octax/Pong-v0"] == ["octax/Pong-v0", "timing", "3 (1,4)", "verified", "Pong (1 player)"]
    assert rows["octax/Rocket-v0"][2] == "2 (F)"  # keys in hex
    for game in list_games():
        spec = get_spec(game)
        actions = f"{len(spec.action_keys) + 1} ({','.join(f'{k:X}' for k in spec.action_keys)})"
        assert rows[env_id(game)][1:4] == [spec.category, actions, "verified"]
    assert f"{len(list_games())} games, {len(list_games())} ROMs present and verified" in out


def test_list_marks_missing_roms_and_says_how_to_get_them(no_roms, capsys):
    assert cli.main(["list"]) == 0
    out = capsys.readouterr().out
    assert {row[3] for row in _rows(out).values()} == {"missing"}
    assert "0 ROMs present and verified" in out and "octax-gym roms install" in out


def test_list_flags_a_rom_with_the_wrong_hash(no_roms, tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / get_spec("Pong").rom_file).write_bytes(b"not pong")
    cli.main(["list"])
    rows = _rows(capsys.readouterr().out)
    assert rows["octax/Pong-v0"][3] == "BAD SHA-1" and rows["octax/Brix-v0"][3] == "missing"


@pytest.mark.parametrize("category", CATEGORIES)
def test_list_category_filter_keeps_exactly_that_category(category, capsys):
    assert cli.main(["list", "--category", category.upper()]) == 0
    rows = _rows(capsys.readouterr().out)
    expected = [env_id(g) for g in list_games() if get_spec(g).category == category]
    assert expected and list(rows) == expected
    assert {row[1] for row in rows.values()} == {category}


def test_list_suite_filter(capsys):
    assert cli.main(["list", "--suite", "ours", "--category", "reaction"]) == 0
    rows = _rows(capsys.readouterr().out)
    assert list(rows) == [env_id(g) for g in list_games(suite="ours") if get_spec(g).category == "reaction"] != []
    assert cli.main(["list", "--suite", "nes"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and "unknown suite 'nes'; valid: 'octax', 'ours', 'archive'" in captured.err


def test_list_unknown_category_is_a_usage_error_naming_the_valid_ones(capsys):
    assert cli.main(["list", "--category", "arcade"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "unknown category 'arcade'" in captured.err
    assert all(category in captured.err for category in CATEGORIES)


def test_info_pong_shows_ids_actions_spaces_and_rom(octax_rom_dir, capsys):
    assert cli.main(["info", "Pong"]) == 0
    out = capsys.readouterr().out
    lines = [line.rstrip() for line in out.splitlines()]
    assert lines[0] == "Pong (1 player)  (octax/Pong-v0, game id 'Pong', version 0)"
    actions = lines.index("actions:           Discrete(3); action i holds its key for the whole step")
    assert [line.split() for line in lines[actions + 1:actions + 4]] == [
        ["0", "no", "key"], ["1", "CHIP-8", "key", "1"], ["2", "CHIP-8", "key", "4"]]
    for expected in ("category:          timing", "platform:          chip8", "Box(0, 1, (4, 32, 64), uint8)",
                     "quirks:            chip8: vf_reset=True", "timers:            real, 60 Hz",
                     "max_episode_steps: 4500", "lives:             no: info['lives'] is -1",
                     "rom:               Pong (1 player).ch8",
                     f"rom sha1:          {get_spec('Pong').rom_sha1}",
                     "rom status:        verified at ", "startup:           95 frames (no key)"):
        assert expected in out, expected


def test_info_takes_gymnasium_ids_and_any_case(capsys):
    cli.main(["info", "Pong"])
    by_id = capsys.readouterr().out
    assert cli.main(["info", "octax/Pong-v0"]) == 0
    assert capsys.readouterr().out == by_id
    assert cli.main(["info", "pong"]) == 0
    assert capsys.readouterr().out == by_id


def test_info_shows_lives_frozen_timers_and_startup_keys(capsys):
    lives_game = next(g for g in list_games() if get_spec(g).lives_fn is not None)
    cli.main(["info", lives_game])
    assert "lives:             yes: info['lives'] counts them" in capsys.readouterr().out
    cli.main(["info", "VerticalBrix"])  # starts by holding key 7 for 250 frames
    assert "startup:           250 frames holding key 7, then 1 frame (no key)" in capsys.readouterr().out


def test_info_shows_an_xochip_game_s_platform_and_observation(monkeypatch, capsys):
    xochip = dataclasses.replace(get_spec("Pong"), platform="xochip", quirks=None)  # no registered game is one yet
    monkeypatch.setattr(game_names, "resolve_spec", lambda name: xochip)
    assert cli.main(["info", "Pong"]) == 0
    out = capsys.readouterr().out
    for expected in ("platform:          xochip", "Box(0, 3, (4, 64, 128), uint8)", "quirks:            xochip: vf_reset=False"):
        assert expected in out, expected


def test_info_shows_frozen_timers(monkeypatch, capsys):
    frozen = dataclasses.replace(get_spec("Pong"), freeze_timers=True)  # no registered game freezes them
    monkeypatch.setattr(game_names, "resolve_spec", lambda name: frozen)
    assert cli.main(["info", "Pong"]) == 0
    assert "timers:            frozen: delay and sound zeroed after every step" in capsys.readouterr().out


def test_info_missing_rom_says_so_and_how_to_fix(no_roms, capsys):
    assert cli.main(["info", "Pong"]) == 0
    out = capsys.readouterr().out
    assert "rom status:        missing\n" in out and "octax-gym roms install" in out


@pytest.mark.parametrize("name", ["Pongg", "octax/Pong-v1", "octax/Pong", ""])
def test_info_unknown_game_fails_listing_the_valid_ids(name, capsys):
    assert cli.main(["info", name]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"octax-gym: error: unknown game {name!r}")
    assert all(game in captured.err for game in list_games()) and "octax/Airplane-v0" in captured.err


def test_info_and_list_never_build_an_env(monkeypatch, capsys):
    def no_env(*args, **kwargs):
        raise AssertionError("list/info must not boot a ROM")

    monkeypatch.setattr(core_env.Env, "__init__", no_env)
    assert cli.main(["info", "Tetris"]) == 0
    assert cli.main(["list"]) == 0
    assert "octax/Tetris-v0" in capsys.readouterr().out


def test_list_runs_as_a_command():
    result = subprocess.run([sys.executable, "-m", "octax_gym", "list", "--category", "reaction"],
                            capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr
    assert "octax/Airplane-v0" in result.stdout and "octax/Pong-v0" not in result.stdout


def test_info_and_list_show_an_archive_game_s_own_speed(capsys):
    assert cli.main(["info", "SuperPong"]) == 0
    out = capsys.readouterr().out
    assert "step:              4 frames x 30 instructions (15 steps per second of game time)" in out  # its tickrate
    assert "rom:               archive/superpong.ch8" in out and "verified" in out
    assert cli.main(["list", "--suite", "archive"]) == 0
    rows = [line.split()[0] for line in capsys.readouterr().out.splitlines()[1:] if line.startswith("octax/")]
    assert rows == [env_id(game) for game in list_games(suite="archive")]
