"""Your own game end to end: Octo source -> assemble -> GameSpec -> register_game -> gymnasium."""

from __future__ import annotations

import hashlib

import gymnasium as gym
import numpy as np
import pytest

import octax_core
import octax_gym
from octax_core.env.games.spec import register_value

# Holding key 5 counts V5 up; at 10 the game sets VE (game over) and stops counting.
SOURCE = """
: main
  loop
    v1 := 5
    if vE == 0 begin
      if v1 key then v5 += 1
      if v5 == 10 then vE := 1
    end
  again
"""


@pytest.fixture(scope="module")
def tiny_game(tmp_path_factory):
    rom = octax_core.assemble(SOURCE)
    path = tmp_path_factory.mktemp("roms") / "tiny.ch8"
    path.write_bytes(rom)
    spec = octax_core.GameSpec(
        id="TinyCounter", title="Tiny counter", rom_file="tiny.ch8",
        rom_sha1=hashlib.sha1(rom).hexdigest(), action_keys=(5,),
        score_fn=lambda state: register_value(state, 5),
        terminated_fn=lambda state: state.V[14] == 1,
        category="reaction", description="Hold key 5 to count to 10.", max_episode_steps=50)
    return spec, path


def test_register_game_makes_single_and_vector_envs(tiny_game):
    spec, path = tiny_game
    gym_id = octax_gym.register_game(spec, rom=path)
    assert gym_id == "octax/TinyCounter-v0"

    env = gym.make(gym_id)
    env.reset(seed=0)
    _, reward, terminated, _, _ = env.step(0)
    assert (reward, terminated) == (0.0, False)  # no key: no count
    total, steps = 0.0, 0
    while not terminated:
        _, reward, terminated, _, _ = env.step(1)
        total, steps = total + reward, steps + 1
        assert steps < 50
    assert total == 10.0
    env.close()

    envs = gym.make_vec(gym_id, num_envs=3)
    envs.reset(seed=1)
    _, rewards, terminated, _, _ = envs.step(np.array([1, 0, 1]))
    assert rewards[1] == 0 and rewards[0] == rewards[2] > 0
    envs.close()


def test_register_game_refuses_builtin_ids_and_missing_files(tiny_game, tmp_path):
    spec, _ = tiny_game
    import dataclasses

    with pytest.raises(ValueError, match="built-in game's id"):
        octax_gym.register_game(dataclasses.replace(spec, id="Pong"))
    with pytest.raises(FileNotFoundError, match="ROM file not found"):
        octax_gym.register_game(spec, rom=tmp_path / "missing.ch8")
    with pytest.raises(TypeError, match="expects a GameSpec"):
        octax_gym.register_game("TinyCounter")


def test_wrong_rom_for_the_spec_is_refused(tiny_game, tmp_path):
    spec, _ = tiny_game
    other = tmp_path / "other.ch8"
    other.write_bytes(octax_core.assemble(": main jump main"))
    import dataclasses

    gym_id = octax_gym.register_game(dataclasses.replace(spec, id="TinyCounterBadRom"), rom=other)
    with pytest.raises(Exception, match="SHA-1|sha1|hash"):
        gym.make(gym_id)
