"""The archive suite: at least 30 games of the Chip8 Community Archive, each with the platform,
quirks, speed and colours its programs.json gives, its ROM shipped in the package and verified,
an id that says its title and clashes with no other game, and a documented module.

Every game is played in tests/archive_games/ (marked slow: `make test-slow`); here the registry's
promises, and the env contract on one game per platform.
"""

from __future__ import annotations

import importlib
import json
import pkgutil
import re

import pytest

import octax_core
from octax_core.emulator.quirks import quirks_from_octo
from octax_core.env import suite_of
from octax_core.env.games.archive._program import archive_palette
from octax_core.env.romstore import ARCHIVE_ROM_DIR, find_rom, sha1_hex
from octax_core.env.testing import check_env

ARCHIVE = octax_core.list_games(suite="archive")
PROGRAMS = json.loads((ARCHIVE_ROM_DIR / "programs.json").read_text())
SHA1SUMS = dict(reversed(line.split()) for line in (ARCHIVE_ROM_DIR / "SHA1SUMS").read_text().splitlines() if line)


def program_of(game_id: str) -> str:
    return octax_core.get_spec(game_id).rom_file.removeprefix("archive/").removesuffix(".ch8")


def camel(title: str) -> str:
    """The id rule: the title's words, capitalised, ASCII letters and digits only."""
    words = re.findall(r"[A-Za-z0-9]+", title.replace("'", ""))
    return "".join(w[0].upper() + w[1:] for w in words)


def test_at_least_30_games_from_every_platform():
    assert len(ARCHIVE) >= 30, ARCHIVE
    platforms = {octax_core.get_spec(g).platform for g in ARCHIVE}
    assert platforms == {"chip8", "schip", "xochip"}


def test_ids_are_titles_and_clash_with_no_other_suite():
    others = set(octax_core.list_games(suite="octax")) | set(octax_core.list_games(suite="ours"))
    for game_id in ARCHIVE:
        spec = octax_core.get_spec(game_id)
        assert suite_of(game_id) == "archive"
        base = camel(PROGRAMS[program_of(game_id)]["title"])
        assert game_id in (base, base + "Archive") and re.fullmatch(r"[A-Za-z0-9]+", game_id), game_id
        assert (game_id == base + "Archive") == (base in others), f"{game_id}: 'Archive' only where {base} is taken"


def test_every_game_takes_its_programs_json_options():
    for game_id in ARCHIVE:
        spec, entry = octax_core.get_spec(game_id), PROGRAMS[program_of(game_id)]
        assert spec.platform == entry["platform"], game_id
        assert spec.quirks == quirks_from_octo(entry["options"]), game_id
        assert spec.instructions_per_frame == int(entry["options"]["tickrate"]), game_id
        assert spec.palette == archive_palette(program_of(game_id)), game_id  # None: the program names no colours
        assert (spec.palette is None) == ("fillColor" not in entry["options"]), game_id


def test_make_takes_the_games_speed_unless_told():
    from octax_core.env.config import make_config

    spec = octax_core.get_spec("SuperPong")
    assert make_config(spec)[0].instructions_per_frame == spec.instructions_per_frame == 30
    assert make_config(spec, instructions_per_frame=7)[0].instructions_per_frame == 7
    assert make_config(octax_core.get_spec("Pong"))[0].instructions_per_frame == 11  # no speed of its own


def test_every_rom_ships_in_the_package_and_is_verified(monkeypatch, tmp_path):
    monkeypatch.delenv("OCTAX_ROM_DIR", raising=False)
    monkeypatch.setenv("OCTAX_DATA_DIR", str(tmp_path))  # an empty user folder: only the package's ROMs
    for game_id in ARCHIVE:
        spec = octax_core.get_spec(game_id)
        path = find_rom(spec)
        assert path.parent == ARCHIVE_ROM_DIR and spec.rom_sha1 == SHA1SUMS[path.name] == sha1_hex(path.read_bytes())


def test_every_module_documents_its_games():
    import octax_core.env.games.archive as package

    documented = set()
    for module in pkgutil.iter_modules(package.__path__):
        if module.name.startswith("_"):
            continue
        games = importlib.import_module(f"{package.__name__}.{module.name}")
        doc = games.__doc__ or ""
        for section in ("### Observation", "### Actions", "### Reward", "### Termination"):
            assert section in doc, f"{module.name}: no {section}"
        documented |= {spec.id for spec in games.SPECS}
    # the two-player games that are no one-player env (TankArchive, ...) are documented too
    assert sorted(documented) == sorted(set(ARCHIVE) | set(octax_core.list_games(suite="archive", players=2)))
    for game_id in ARCHIVE:
        spec = octax_core.get_spec(game_id)
        assert spec.description and spec.title and spec.category in octax_core.env.games.CATEGORIES


def test_the_docs_gallery_lists_every_archive_game():
    import runpy
    from pathlib import Path

    docs = Path(__file__).resolve().parents[2] / "docs"
    gallery = runpy.run_path(str(docs / "gallery.py"))
    page = (docs / "gallery.md").read_text()
    assert gallery["registry_rows"]() == gallery["page_rows"](page), "docs/gallery.md is stale: run python docs/gallery.py"


def test_every_archive_program_is_a_game_or_left_out_with_a_reason():
    import runpy
    from pathlib import Path

    from octax_core.env.games.archive._program import programs

    gallery = runpy.run_path(str(Path(__file__).resolve().parents[2] / "docs" / "gallery.py"))
    registered = [gallery["program_name"](octax_core.get_spec(g)) for g in ARCHIVE]
    left_out = [name for names, why in gallery["LEFT_OUT"] for name in names]
    assert all(why for names, why in gallery["LEFT_OUT"])
    assert sorted(list(set(registered)) + left_out) == sorted(programs()), "a program is neither a game nor left out (or both)"


# XO-CHIP's contract runs in make test on Civiliz8n (test_contract_takes_xochip_plane_codes, the
# same check_env); its cheapest game's in make test-slow. So does CHIP-8's: make test runs the
# contract on three CHIP-8 games (test_all_games.py: Pong, Blinky, Duel), and here on SUPER-CHIP's
# cheapest game, which has the archive's quirks (Octo's, as the CHIP-8 one's).
@pytest.mark.parametrize("platform", [pytest.param("chip8", marks=pytest.mark.slow), "schip",
                                      pytest.param("xochip", marks=pytest.mark.slow)])
def test_contract_on_one_game_per_platform(platform):
    """The cheapest game of each platform (fewest instructions per frame); every game: tests/archive_games.

    One env: the batch of one is also the env run alone, so check_env compiles one step, not two.
    That env i of a batch plays what it plays alone is checked on an archive game by
    test_contract_takes_xochip_plane_codes (Civiliz8n, 2 envs at 100 instructions a frame, where
    idle skipping could let the batch leak in), and each platform's machine by the emulator's batch
    tests (tests/core_emulator/test_platforms.py, test_vmap.py)."""
    game_id = min((g for g in ARCHIVE if octax_core.get_spec(g).platform == platform),
                  key=lambda g: (octax_core.get_spec(g).instructions_per_frame, g))
    check_env(game_id, num_envs=1, steps=3)


def test_every_programs_colours_parse():
    from octax_core.env.games.archive._program import _rgb, programs

    assert _rgb("#FFAA00") == (255, 170, 0) and _rgb("#fa0") == (255, 170, 0) and _rgb("lightcyan") == (224, 255, 255)
    for name, entry in programs().items():
        palette = archive_palette(name)
        assert palette is None or len(palette) == (4 if entry["platform"] == "xochip" else 2), name
    with pytest.raises(ValueError, match="colour 'mauve': not '#RRGGBB', '#RGB' or one of aquamarine"):
        _rgb("mauve")


@pytest.mark.parametrize("obs_scale", [1, pytest.param(255, marks=pytest.mark.slow)])
def test_contract_takes_xochip_plane_codes(obs_scale):
    """Civiliz8n's title lights both planes: codes 0..3 (x 85 at obs_scale 255), which the contract allows."""
    check_env("Civiliz8n", num_envs=2, steps=2, obs_scale=obs_scale)


def test_survival_reward_pays_each_step_the_game_goes_on():
    """Flight Runner (the archive's) keeps no score: +1 a step while it flies, nothing once ended."""
    import jax

    env, params = octax_core.make("FlightRunnerArchive")
    _, state = env.reset(jax.random.key(0), params)
    step = jax.jit(env.step)
    rewards, ended = [], False
    for t in range(400):
        _, state, reward, terminated, truncated, info = step(jax.random.key(t), state, 0, params)
        rewards.append(float(reward))
        assert float(info["score"]) == 0.0
        if bool(terminated):
            ended = True
            break
    assert ended and rewards[-1] == 0.0 and set(rewards[:-1]) == {1.0}
    _, _, reward, *_ = step(jax.random.key(999), state, 0, params)
    assert float(reward) == 0.0  # an ended episode stands still
    assert octax_core.get_spec("Pong").survival_reward == 0.0
