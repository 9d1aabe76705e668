"""One game-name resolver (octax_gym/envs/game_names.py) behind every place that takes a game by name.

Nothing here builds an env: the resolver reads the registry, and the entry points refuse an
unknown name before they compile anything (`compiled_step.build` is stubbed where a good name
would go on to compile).
"""

from __future__ import annotations

import dataclasses
import re

import pytest

from octax_core.env.games import get_spec, list_games
from octax_gym import UnknownOptionError, cli, env_id, video
from octax_gym.envs.game_names import resolve_env_id, resolve_spec
from octax_gym.step import compiled_step


@pytest.mark.parametrize("name", ["Pong", "pong", "PONG", "octax/Pong-v0", "OCTAX/pong-V0"])
def test_every_accepted_spelling_gives_the_game(name):
    assert resolve_spec(name) is get_spec("Pong")
    assert resolve_env_id(name) == "octax/Pong-v0"


def test_archive_games_resolve_like_the_others():
    archive = list_games("archive")[0]
    assert resolve_spec(archive.lower()) is get_spec(archive)
    assert resolve_env_id(env_id(archive).upper()) == env_id(archive)


def test_a_game_spec_is_taken_as_it_is_and_other_types_are_refused():
    own = dataclasses.replace(get_spec("Pong"), id="MyPong")  # not in the registry
    assert resolve_spec(own) is own and resolve_env_id(own) == "octax/MyPong-v0"
    with pytest.raises(TypeError, match="game must be a registered id"):
        resolve_spec(3)


@pytest.mark.parametrize("name, close", [("Pongg", "'Pong'"), ("octax/Pong-v9", "'octax/Pong-v0'"),
                                         ("tetriss", "'Tetris'"), ("", None)])
def test_an_unknown_name_lists_the_close_matches_and_every_id(name, close):
    with pytest.raises(UnknownOptionError) as info:
        resolve_spec(name)
    message = str(info.value)
    hint = f" (did you mean {close}" if close else ""
    assert message.startswith(f"unknown game {name!r}{hint}")
    assert all(repr(game) in message for game in list_games())
    assert message.endswith(f"or their Gymnasium ids ({env_id(list_games()[0])}, ...)")
    assert isinstance(info.value, KeyError)  # as the core registry's lookup raised


def test_the_envs_resolve_names_the_same_way(monkeypatch):
    built = []
    monkeypatch.setattr(compiled_step, "_compiled_step", lambda spec, config, rom: built.append(spec) or "stub")
    for name in ("pong", "octax/Pong-v0"):
        assert compiled_step.build(name, None, {})[0] == "stub"
    assert built == [get_spec("Pong")] * 2


def test_every_entry_point_gives_the_resolver_s_error(tmp_path, capsys):
    with pytest.raises(UnknownOptionError) as info:
        resolve_spec("Pongg")
    expected = str(info.value)
    with pytest.raises(UnknownOptionError, match="^" + re.escape(expected) + "$"):
        compiled_step.build("Pongg", None, {})
    with pytest.raises(UnknownOptionError, match="^" + re.escape(expected) + "$"):
        video.record("Pongg", tmp_path / "v.mp4", steps=1, progress=False)
    commands = [["info", "Pongg"], ["record", "Pongg", "--steps", "1", "--out", str(tmp_path / "v.mp4")],
                ["trace", "Pongg"]]
    try:
        import minari  # noqa: F401
        commands.append(["dataset", "collect", "Pongg", "--dataset-id", "octax/x-v0", "--steps", "1"])
    except ImportError:
        pass
    for argv in commands:
        assert cli.main(argv) == 1
        err = capsys.readouterr().err
        assert err.startswith(f"octax-gym: error: {expected}"), argv  # trace adds "or the path of a ROM file"


def test_the_dataset_collector_gives_the_resolver_s_error():
    pytest.importorskip("minari")
    from octax_gym.datasets import collect_dataset

    with pytest.raises(UnknownOptionError, match=r"^unknown game 'Pongg' \(did you mean 'Pong'\?\)"):
        collect_dataset("Pongg", "octax/x-v0", 1)
