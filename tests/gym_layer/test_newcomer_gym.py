"""What a Gymnasium or ale-py user tries first, on the single env, the vector env and the core:
the episode bound in `env.spec`, `get_action_meanings()`, `render_mode="human"` refused at make,
int8 action masks that `action_space.sample(mask=...)` takes, `__version__`, and an unknown game
named with its close match by the core as by the Gymnasium layer (issue 39, "the small things").

Every env here is a hand-worked test game (tests/counter_game.py, tests/two_player_games.py), so
each compile is small; the Counter never ends with no key held, so only the bound cuts it.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import tomllib
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import octax_core
import octax_gym
from octax_core.env.games import UnknownGameError, get_spec, list_games
from octax_gym import OctaxEnv, OctaxVectorEnv, UnknownOptionError
from octax_gym.envs.game_names import resolve_spec

from counter_game import COUNTER
from two_player_games import TAKE_TURNS, TWO_COUNTERS

REPO = Path(__file__).resolve().parents[2]
BOUND = COUNTER.max_episode_steps  # 50


@pytest.fixture(scope="module")
def counter_id(counter_rom):
    return octax_gym.register_game(COUNTER, rom=counter_rom)


def steps_to_truncation(env, limit: int) -> int:
    """Steps with no key held until `truncated`, from a fresh episode (at most `limit`)."""
    env.reset(seed=0)
    for step in range(1, limit + 1):
        _, _, terminated, truncated, _ = env.step(0)
        assert not terminated
        if truncated:
            return step
    return limit + 1


# --- env.spec.max_episode_steps ---------------------------------------------------------------

def test_every_registered_spec_has_its_game_s_episode_bound():
    for game in sorted(set(list_games()) | set(list_games(players=2))):
        assert gym.spec(octax_gym.env_id(game)).max_episode_steps == get_spec(game).max_episode_steps, game
    assert gym.spec("octax/Pong-v0").max_episode_steps == 4500
    assert gym.spec(octax_gym.MIX_ENV_ID).max_episode_steps is None  # each game of a mix keeps its own


def test_make_cuts_episodes_where_the_spec_says_with_one_time_limit(counter_id):
    env = gym.make(counter_id)
    assert env.spec.max_episode_steps == BOUND
    limits = [wrapper for wrapper in _chain(env) if isinstance(wrapper, gym.wrappers.TimeLimit)]
    assert len(limits) == 1  # Gymnasium's, counting alone: the env's own bound is lifted
    assert steps_to_truncation(env, BOUND + 5) == BOUND
    env.close()


def test_make_with_a_longer_bound_is_not_cut_at_the_game_s(counter_id):
    env = gym.make(counter_id, max_episode_steps=BOUND + 10)
    assert env.spec.max_episode_steps == BOUND + 10
    assert steps_to_truncation(env, BOUND + 15) == BOUND + 10
    env.close()
    env = gym.make(counter_id, max_episode_steps=-1)  # Gymnasium's "no TimeLimit": no bound at all
    assert env.spec.max_episode_steps is None
    assert steps_to_truncation(env, BOUND + 5) == BOUND + 6
    env.close()


def test_make_vec_counts_the_bound_once_inside_the_step(counter_id):
    envs = gym.make_vec(counter_id, num_envs=2)
    assert envs.spec.max_episode_steps == BOUND and int(envs.params.max_episode_steps) == BOUND
    envs.close()
    assert int(gym.make_vec(counter_id, num_envs=2, max_episode_steps=7).params.max_episode_steps) == 7


def test_an_env_built_directly_or_with_the_bound_in_its_kwargs_keeps_its_own(counter_rom, counter_id):
    assert OctaxEnv(COUNTER, rom=counter_rom).spec is None  # no gymnasium.make, no spec (as in Gymnasium)
    spec = dataclasses.replace(gym.spec(counter_id), max_episode_steps=None,
                               kwargs={**gym.spec(counter_id).kwargs, "max_episode_steps": 12})
    env = gym.make(spec)  # a dataset's recovered spec: the bound in the kwargs, no TimeLimit
    assert env.spec.max_episode_steps == 12
    assert steps_to_truncation(env, 20) == 12
    env.close()


def _chain(env):
    while True:
        yield env
        if not isinstance(env, gym.Wrapper):
            return
        env = env.env


# --- get_action_meanings ------------------------------------------------------------------------

def test_action_meanings_name_no_op_and_each_action_s_key(counter_rom, counter_id, two_counters_rom):
    env = gym.make(counter_id)
    assert env.unwrapped.get_action_meanings() == ["NOOP", "KEY_1", "KEY_2"]
    assert len(env.unwrapped.get_action_meanings()) == env.action_space.n
    env.close()
    learner = OctaxEnv(TWO_COUNTERS, rom=two_counters_rom, opponent="noop", seat=1)
    assert learner.get_action_meanings() == ["NOOP", "KEY_4", "KEY_5"]  # the learner seat's keys
    assert octax_gym.env.action_meanings(get_spec("Pong")) == ["NOOP"] + [f"KEY_{k:X}" for k in
                                                                         get_spec("Pong").action_keys]


# --- render_mode="human" --------------------------------------------------------------------------

def test_human_rendering_is_refused_at_make_naming_the_alternatives(counter_id, counter_rom):
    with pytest.raises(UnknownOptionError) as info:
        gym.make(counter_id, render_mode="human")  # at make, not at the first reset
    message = str(info.value)
    assert message.startswith("unknown render_mode 'human'; valid: None, 'rgb_array', and not 'human'")
    assert "octax-gym play" in message and "octax_gym.video" in message and "HumanRendering" in message
    with pytest.raises(UnknownOptionError, match="octax-gym play"):
        OctaxEnv(COUNTER, rom=counter_rom, render_mode="human")
    with pytest.raises(UnknownOptionError, match="RenderCollection over render_mode='rgb_array'"):
        gym.make(counter_id, render_mode="rgb_array_list")  # the other mode Gymnasium would emulate
    env = gym.make(counter_id, render_mode="rgb_array")
    assert env.metadata["render_modes"] == ["rgb_array"] and env.render_mode == "rgb_array"
    env.close()


# --- action masks ---------------------------------------------------------------------------------

def test_the_one_seat_views_masks_are_int8_and_sample_legal_actions(take_turns_rom):
    env = OctaxEnv(TAKE_TURNS, rom=take_turns_rom, opponent="noop", seat=1)
    _, info = env.reset(seed=0)
    assert info["action_mask"].dtype == np.int8 and info["action_mask"].tolist() == [1, 0]  # seat 0 moves first
    assert env.action_space.sample(mask=info["action_mask"]) == 0
    assert env.action_masks().dtype == np.bool_  # what MaskablePPO reads
    # one env, autoreset disabled: test_opponent's turn-based single env's compiled step (random opponent)
    envs = OctaxVectorEnv(TAKE_TURNS, 1, rom=take_turns_rom, opponent="random", autoreset_mode="disabled")
    _, info = envs.reset(seed=0)
    assert info["action_mask"].dtype == np.int8
    for _ in range(6):
        actions = envs.action_space.sample(mask=tuple(info["action_mask"]))
        assert all(info["action_mask"][row, action] for row, action in enumerate(actions))
        _, _, _, _, info = envs.step(actions)  # a closed action would raise IllegalMoveError


# --- __version__ ----------------------------------------------------------------------------------

def test_version_is_the_installed_distribution_s_and_pyproject_s():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert octax_gym.__version__ == octax_core.__version__ == importlib.metadata.version(project["name"])
    assert octax_gym.__version__ == project["version"]  # an install older than pyproject.toml fails here


# --- unknown games in the core --------------------------------------------------------------------

@pytest.mark.parametrize("make, typo, close", [
    (octax_core.make, "Pongg", "Pong"),
    (lambda name: octax_core.make_mix(["Brix", name]), "Pongg", "Pong"),
    (octax_core.make_multi, "Duell", "Duel"),
    (octax_core.get_spec, "tetriss", "Tetris"),
])
def test_the_core_names_the_close_match_without_listing_every_game(make, typo, close):
    with pytest.raises(UnknownGameError) as info:
        make(typo)
    message = str(info.value)
    assert message.startswith(f"unknown game {typo!r}; did you mean {close!r}?")
    assert "list_games()" in message and len(message) < 200 and "'Airplane'" not in message
    assert isinstance(info.value, KeyError) and isinstance(info.value, ValueError)
    assert info.value.suggestions == (close,)


def test_both_layers_suggest_the_same_games():
    for typo in ("Pongg", "BRIXX", "SpaceRacr", "Cavern9", "xyzzy"):
        with pytest.raises(UnknownGameError) as core:
            octax_core.get_spec(typo)
        with pytest.raises(UnknownOptionError) as gym_layer:
            resolve_spec(typo)
        hint = " or ".join(map(repr, core.value.suggestions))
        assert (f"(did you mean {hint}?)" in str(gym_layer.value)) == bool(hint), typo
