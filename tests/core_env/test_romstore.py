"""The ROM store: lookup order, hash refusal, error messages, import and install (octax_core/env/romstore.py)."""

from __future__ import annotations

import os
import subprocess
import zipfile
from pathlib import Path

import pytest
from shared_data import SHARED
from fake_games import make_spec, read_sha1sums, sha1, specs_from_sha1sums

from octax_core import Rom
from octax_core.env import romstore
from octax_core.env.games import get_spec, list_games
from octax_core.env.romstore import RomHashError, RomInstallError, RomNotFoundError

PONG = b"\x00\xe0\x12\x00pong"
BRIX = b"\x00\xe0\x12\x00brix"
OTHER = b"\x00\xe0\x12\x00not a game of ours"
SHARED_OCTAX = SHARED / "roms" / "octax"
REAL_PROJECT_ROM_DIR = romstore.PROJECT_ROM_DIR  # before the autouse fixture swaps it
# The games whose ROMs are third-party, in the shared store; ours are built in roms/ (test_own_roms.py).
THIRD_PARTY_GAMES = [g for g in list_games() if not (REAL_PROJECT_ROM_DIR / get_spec(g).rom_file).is_file()]


@pytest.fixture(autouse=True)
def store(tmp_path, monkeypatch):
    """An isolated store: data dir under tmp_path, no OCTAX_ROM_DIR, no project roms/."""
    monkeypatch.setenv("OCTAX_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.delenv("OCTAX_ROM_DIR", raising=False)
    monkeypatch.delenv("XDG_DATA_HOME", raising=False)
    monkeypatch.setattr(romstore, "PROJECT_ROM_DIR", tmp_path / "project" / "roms")
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.fixture
def pong():
    return make_spec("Pong", "Pong (1 player).ch8", PONG)


@pytest.fixture
def brix():
    return make_spec("Brix", "Brix.ch8", BRIX)


def put(folder: Path, name: str, data: bytes) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_bytes(data)
    return folder / name


# --- where the store looks -------------------------------------------------------------------

def test_user_rom_dir_prefers_octax_data_dir_then_xdg_then_home(tmp_path, monkeypatch):
    assert romstore.user_rom_dir() == (tmp_path / "data" / "roms").resolve()
    monkeypatch.delenv("OCTAX_DATA_DIR")
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    assert romstore.user_rom_dir() == (tmp_path / "xdg" / "octax-gym" / "roms").resolve()
    monkeypatch.setenv("XDG_DATA_HOME", "relative/xdg")  # the XDG spec says: ignore relative paths
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert romstore.user_rom_dir() == (tmp_path / "home" / ".local" / "share" / "octax-gym" / "roms").resolve()


def test_search_dirs_order_env_list_then_user_then_project(tmp_path, monkeypatch):
    assert romstore.search_dirs() == [romstore.user_rom_dir()]  # project roms/ absent: not listed
    (tmp_path / "project" / "roms").mkdir(parents=True)
    monkeypatch.setenv("OCTAX_ROM_DIR", os.pathsep.join(["rel", "", str(tmp_path / "abs"), "rel"]))
    assert romstore.search_dirs() == [
        tmp_path.resolve() / "rel", tmp_path.resolve() / "abs", romstore.user_rom_dir(),
        tmp_path / "project" / "roms",
    ]


def test_real_project_roms_dir_is_the_package_roms_folder_whose_own_roms_are_the_repository_s():
    assert REAL_PROJECT_ROM_DIR.name == "roms"
    assert (REAL_PROJECT_ROM_DIR.parent / "romstore.py").is_file()
    repository_roms = REAL_PROJECT_ROM_DIR.parents[2] / "roms"
    for name in ("dodge.ch8", "flak.ch8"):  # links into roms/, where the Octo sources build them
        assert (REAL_PROJECT_ROM_DIR / name).resolve() == (repository_roms / name).resolve()


@pytest.mark.parametrize("holders, winner", [
    (("env_a", "env_b", "user", "project"), "env_a"),
    (("env_b", "user", "project"), "env_b"),
    (("user", "project"), "user"),
    (("project",), "project"),
])
def test_find_rom_takes_the_first_folder_in_lookup_order(tmp_path, monkeypatch, pong, holders, winner):
    dirs = {"env_a": tmp_path / "a", "env_b": tmp_path / "b", "user": romstore.user_rom_dir(),
            "project": tmp_path / "project" / "roms"}
    monkeypatch.setenv("OCTAX_ROM_DIR", os.pathsep.join([str(dirs["env_a"]), str(dirs["env_b"])]))
    for holder in holders:
        put(dirs[holder], pong.rom_file, PONG)
    assert romstore.find_rom(pong) == dirs[winner] / pong.rom_file


def test_load_game_rom_returns_the_verified_bytes(pong):
    put(romstore.user_rom_dir(), pong.rom_file, PONG)
    rom = romstore.load_game_rom(pong)
    assert isinstance(rom, Rom)
    assert rom.data == PONG and rom.name == pong.rom_file and rom.sha1 == pong.rom_sha1


def test_uppercase_hash_in_spec_is_accepted():
    spec = make_spec("Pong", "p.ch8", PONG)
    spec = type(spec)(**{**spec.__dict__, "rom_sha1": spec.rom_sha1.upper()})
    put(romstore.user_rom_dir(), "p.ch8", PONG)
    assert romstore.load_game_rom(spec).data == PONG


# --- refusals and errors ---------------------------------------------------------------------

def test_a_wrong_hash_earlier_in_the_order_is_refused_not_skipped(tmp_path, monkeypatch, pong):
    monkeypatch.setenv("OCTAX_ROM_DIR", str(tmp_path / "env"))
    bad = put(tmp_path / "env", pong.rom_file, PONG + b"\x00")
    put(romstore.user_rom_dir(), pong.rom_file, PONG)  # a good copy later does not excuse it
    with pytest.raises(RomHashError) as err:
        romstore.load_game_rom(pong)
    message = str(err.value)
    assert str(bad) in message and pong.rom_sha1 in message and sha1(PONG + b"\x00") in message
    assert "Pong" in message and "octax-gym roms install" in message


def test_explicit_path_skips_the_search_and_is_verified(tmp_path, pong):
    good = put(tmp_path / "elsewhere", "renamed.bin", PONG)
    assert romstore.find_rom(pong, good) == good
    assert romstore.find_rom(pong, str(good)) == good
    assert romstore.load_game_rom(pong, good).data == PONG
    put(tmp_path / "folder", pong.rom_file, PONG)
    assert romstore.find_rom(pong, tmp_path / "folder") == tmp_path / "folder" / pong.rom_file

    bad = put(tmp_path / "elsewhere", "bad.bin", BRIX)
    put(romstore.user_rom_dir(), pong.rom_file, PONG)  # never consulted with an explicit path
    with pytest.raises(RomHashError, match="bad.bin"):
        romstore.find_rom(pong, bad)
    with pytest.raises(RomNotFoundError, match="nope.ch8"):
        romstore.find_rom(pong, tmp_path / "nope.ch8")


def test_missing_rom_error_names_game_file_hash_dirs_and_fix(tmp_path, monkeypatch, pong):
    monkeypatch.setenv("OCTAX_ROM_DIR", str(tmp_path / "not-there"))
    with pytest.raises(RomNotFoundError) as err:
        romstore.load_game_rom(pong)
    assert isinstance(err.value, FileNotFoundError)
    message = str(err.value)
    for needle in ("'Pong'", pong.rom_file, pong.rom_sha1, str(tmp_path / "not-there"),
                   str(romstore.user_rom_dir()), "does not exist", "octax-gym roms install",
                   "octax-gym roms import PATH", "OCTAX_ROM_DIR"):
        assert needle in message


def test_rom_status_reports_verified_bad_and_missing(tmp_path, monkeypatch, pong, brix):
    tetris = make_spec("Tetris", "Tetris.ch8", b"tetris")
    put(romstore.user_rom_dir(), pong.rom_file, PONG)
    put(romstore.user_rom_dir(), brix.rom_file, BRIX + b"!")
    rows = {row.game_id: row for row in romstore.rom_status([pong, brix, tetris])}
    assert rows["Pong"].verified and rows["Pong"].path == romstore.user_rom_dir() / pong.rom_file
    assert not rows["Brix"].verified and rows["Brix"].actual_sha1 == sha1(BRIX + b"!")
    assert rows["Tetris"].path is None and not rows["Tetris"].verified
    assert rows["Tetris"].sha1 == sha1(b"tetris") and rows["Tetris"].rom_file == "Tetris.ch8"


# --- import ----------------------------------------------------------------------------------

def test_import_from_folder_matches_by_hash_not_by_name(tmp_path, pong, brix):
    src = tmp_path / "src"
    put(src / "deep" / "er", "whatever.bin", PONG)   # right bytes, wrong name: installed
    put(src, brix.rom_file, OTHER)                    # right name, wrong bytes: ignored
    put(src, "notes.txt", b"hello")
    results = romstore.import_roms(src, [pong, brix])
    dest = romstore.user_rom_dir()
    assert [(r.game_ids, r.rom_file, r.action, r.path) for r in results] == [
        (("Pong",), pong.rom_file, "installed", dest / pong.rom_file)]
    assert results[0].source == str(src / "deep" / "er" / "whatever.bin")
    assert sorted(p.name for p in dest.iterdir()) == [pong.rom_file]  # no temp files left behind
    assert romstore.find_rom(pong) == dest / pong.rom_file


def test_import_again_is_unchanged_and_repairs_a_corrupted_copy(tmp_path, pong):
    src = put(tmp_path / "src", "a.ch8", PONG).parent
    assert [r.action for r in romstore.import_roms(src, [pong])] == ["installed"]
    assert [r.action for r in romstore.import_roms(src, [pong])] == ["unchanged"]
    (romstore.user_rom_dir() / pong.rom_file).write_bytes(b"corrupted")
    assert [r.action for r in romstore.import_roms(src, [pong])] == ["replaced"]
    assert romstore.load_game_rom(pong).data == PONG


@pytest.mark.parametrize("archive_name, members", [
    ("roms.zip", {"some/dir/pong.ch8": PONG, "brix.ch8": BRIX, "readme.txt": b"x"}),
    ("octax-0.1.1-py3-none-any.whl", {"octax/__init__.py": b"", "octax/roms/x.ch8": PONG,
                                       "roms/Brix.ch8": BRIX, "octax-0.1.1.dist-info/RECORD": b""}),
])
def test_import_from_zip_and_wheel(tmp_path, pong, brix, archive_name, members):
    archive = tmp_path / archive_name
    with zipfile.ZipFile(archive, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    dest = tmp_path / "custom-dest"
    results = romstore.import_roms(archive, [pong, brix], dest=dest)
    assert [(r.rom_file, r.action) for r in results] == [("Brix.ch8", "installed"),
                                                        (pong.rom_file, "installed")]
    assert all(r.source.startswith(f"{archive}:") for r in results)
    assert (dest / pong.rom_file).read_bytes() == PONG and (dest / "Brix.ch8").read_bytes() == BRIX
    assert not romstore.user_rom_dir().exists()


def test_import_a_single_file_and_a_shared_rom(tmp_path):
    a, b = make_spec("A", "shared.ch8", PONG), make_spec("B", "shared.ch8", PONG)
    results = romstore.import_roms(put(tmp_path, "x.ch8", PONG), [a, b])
    assert [(r.game_ids, r.rom_file) for r in results] == [(("A", "B"), "shared.ch8")]


def test_import_installs_nothing_without_a_hash_match(tmp_path, pong):
    src = put(tmp_path / "src", pong.rom_file, OTHER).parent
    assert romstore.import_roms(src, [pong]) == []
    assert not romstore.user_rom_dir().exists()
    with pytest.raises(FileNotFoundError, match="nothing to import"):
        romstore.import_roms(tmp_path / "missing", [pong])


def test_import_refuses_a_registry_giving_one_file_two_hashes(tmp_path):
    specs = [make_spec("A", "same.ch8", PONG), make_spec("B", "same.ch8", BRIX)]
    with pytest.raises(ValueError, match="same.ch8"):
        romstore.import_roms(tmp_path, specs)


# --- install from the package index ----------------------------------------------------------

def fake_pip(monkeypatch, *, returncode=0, wheel=None, timeout=False):
    calls = []

    def run(cmd, **kwargs):
        calls.append((cmd, kwargs))
        if timeout:
            raise subprocess.TimeoutExpired(cmd, kwargs["timeout"])
        if wheel is not None:
            with zipfile.ZipFile(Path(cmd[cmd.index("-d") + 1]) / "octax-0.1.1-py3-none-any.whl", "w") as zf:
                zf.writestr("roms/pong.ch8", wheel)
        return subprocess.CompletedProcess(cmd, returncode, "", "ERROR: No matching distribution")

    monkeypatch.setattr(romstore.subprocess, "run", run)
    return calls


def test_install_from_pypi_runs_pip_download_then_imports(monkeypatch, pong):
    calls = fake_pip(monkeypatch, wheel=PONG)
    results = romstore.install_from_pypi([pong])
    cmd, kwargs = calls[0]
    assert cmd[:4] == [romstore.sys.executable, "-m", "pip", "download"]
    assert {"--no-deps", "--only-binary=:all:", "octax==0.1.1"} <= set(cmd)
    assert kwargs["timeout"] > 0
    assert [r.action for r in results] == ["installed"] and romstore.load_game_rom(pong).data == PONG


@pytest.mark.parametrize("kind, match", [("fail", "(?s)pip download failed .exit 1.*No matching"),
                                         ("timeout", "took over"), ("no wheel", "no octax wheel")])
def test_install_from_pypi_failures_are_clear(monkeypatch, pong, kind, match):
    fake_pip(monkeypatch, returncode=1 if kind == "fail" else 0, timeout=kind == "timeout")
    with pytest.raises(RomInstallError, match=match) as err:
        romstore.install_from_pypi([pong], timeout=5)
    assert kind == "no wheel" or "roms import" in str(err.value)


# --- the real ROMs ---------------------------------------------------------------------------

@pytest.mark.shared
def test_shared_roms_import_cleanly_by_hash(tmp_path):
    octax_rom_dir = SHARED_OCTAX  # with its SHA1SUMS manifest
    specs = specs_from_sha1sums(octax_rom_dir / "SHA1SUMS") + [get_spec(i) for i in THIRD_PARTY_GAMES]
    specs = list({(s.id, s.rom_file): s for s in specs}.values())
    results = romstore.import_roms(octax_rom_dir, specs, dest=tmp_path / "dest")
    assert {r.rom_file for r in results} == {s.rom_file for s in specs}
    for spec in specs:
        assert romstore.find_rom(spec, tmp_path / "dest") == tmp_path / "dest" / spec.rom_file


@pytest.mark.shared
def test_install_from_pypi_gets_the_real_octax_wheel(tmp_path):
    octax_rom_dir = SHARED_OCTAX  # with its SHA1SUMS manifest
    manifest = read_sha1sums(octax_rom_dir / "SHA1SUMS")
    specs = specs_from_sha1sums(octax_rom_dir / "SHA1SUMS")
    try:
        results = romstore.install_from_pypi(specs, dest=tmp_path / "dest", timeout=120)
    except RomInstallError as exc:
        pytest.fail(f"could not download octax==0.1.1 from the package index (network?):\n{exc}")
    installed = {r.rom_file: sha1((tmp_path / "dest" / r.rom_file).read_bytes()) for r in results}
    assert installed == {name: digest for name, digest in manifest.items() if name.endswith(".ch8")}


@pytest.mark.shared
@pytest.mark.parametrize("game_id", THIRD_PARTY_GAMES)
def test_registered_game_rom_is_in_the_shared_store(game_id, monkeypatch):
    octax_rom_dir = SHARED_OCTAX  # with its SHA1SUMS manifest
    spec = get_spec(game_id)
    assert read_sha1sums(octax_rom_dir / "SHA1SUMS").get(spec.rom_file) == spec.rom_sha1.lower()
    monkeypatch.setenv("OCTAX_ROM_DIR", str(octax_rom_dir))
    assert romstore.find_rom(spec).resolve() == (octax_rom_dir / spec.rom_file).resolve()  # ../shared may be a link
