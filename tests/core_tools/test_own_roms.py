"""Our own games in roms/: each committed ROM is exactly what our assembler builds from its source,
and the game specs name those ROMs by their SHA-1 (`make roms` rebuilds them)."""

from pathlib import Path

import pytest

import octax_core
from octax_core.tools.octo import assemble
from octax_core.env.romstore import PROJECT_ROM_DIR, find_rom, sha1_hex

ROMS = Path(__file__).resolve().parents[2] / "roms"
SOURCES = sorted(ROMS.glob("*.8o"))


def test_every_source_has_its_rom_and_no_rom_lacks_a_source():
    assert SOURCES, f"no Octo sources in {ROMS}"
    assert sorted(p.stem for p in ROMS.glob("*.ch8")) == [p.stem for p in SOURCES]


@pytest.mark.parametrize("source", SOURCES, ids=lambda p: p.name)
def test_committed_rom_is_what_the_assembler_builds(source):
    rom = source.with_suffix(".ch8")
    assert assemble(source.read_text(encoding="utf-8")) == rom.read_bytes(), \
        f"{rom.name} is stale: run `make roms` (then update its spec's rom_sha1)"


@pytest.mark.parametrize("source", SOURCES, ids=lambda p: p.name)
def test_specs_name_the_committed_rom_by_hash(source):
    rom = source.with_suffix(".ch8")
    games = set(octax_core.list_games()) | set(octax_core.list_games(players=2))  # two-player-only ones too
    specs = [octax_core.get_spec(g) for g in sorted(games)]
    users = [spec for spec in specs if spec.rom_file == rom.name]
    assert users, f"no game plays {rom.name}"
    for spec in users:
        assert spec.rom_sha1 == sha1_hex(rom.read_bytes()), f"{spec.id}: rom_sha1 is not {rom.name}'s"


def test_the_rom_store_finds_our_roms_in_the_project():
    for name in ("dodge.ch8", "flak.ch8"):  # the package's copies are links to roms/
        assert (PROJECT_ROM_DIR / name).read_bytes() == (ROMS / name).read_bytes()
    for game_id in ("Dodge", "Flak"):
        spec = octax_core.get_spec(game_id)
        assert find_rom(spec).name == spec.rom_file
