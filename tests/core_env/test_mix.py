"""Many games in one batch (`octax_core.make_mix`): each env of a mix plays, step for step, what
`make(game)` plays from the same keys and actions; and the mix's own API and errors."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core

from counter_game import COUNTER
from random_rollouts import random_rollout

# Four CHIP-8 games that differ in every way a mix looks up per game: quirks (Pong: chip8, with
# the VIP's display wait; Blinky: schip; GhostEscape and SpacejamArchive: Octo's), speeds (7, 11
# and 100 instructions a frame, the last skipping idle instructions), keys (1, 2 and 4), a
# survival reward (GhostEscape) and lives (SpacejamArchive; the others keep none). Each game is a
# compile of its own (its `make` rollout), so the mix is the fewest games that cover all of that;
# every one-player game of the registry is checked so in test_mix_every_game.py (slow).
MIXED = ["Pong", "Blinky", "GhostEscape", "SpacejamArchive"]
OPTIONS = dict(noop_max=3, repeat_action_probability=0.25)
STEPS = 40


@pytest.fixture(scope="module")
def mix():
    return octax_core.make_mix(MIXED, **OPTIONS)


@pytest.fixture(scope="module")
def played(mix):
    """Each game's rollouts from its own 3 keys: (by its envs in the mix, by make(game)). One
    compiled program plays them all: the mix once, over a batch holding every game (the game and
    its action count are data), beside each game's single env."""
    env, params = mix
    singles = [octax_core.make(game, **OPTIONS) for game in MIXED]
    keys = jnp.stack([jax.random.split(jax.random.key(index), 3) for index in range(len(MIXED))])
    num_actions = jnp.array([single.num_actions for single, _ in singles])

    @jax.jit
    def play(keys, num_actions):
        in_mix = jax.vmap(jax.vmap(lambda k, n, g: random_rollout(env, params, k, n, STEPS, g), in_axes=(0, None, None)))(
            keys, num_actions, jnp.arange(len(MIXED)))
        alone = [jax.vmap(lambda k: random_rollout(single, single_params, k, single.num_actions, STEPS))(keys[index])
                 for index, (single, single_params) in enumerate(singles)]
        return in_mix, alone

    return play(keys, num_actions)


@pytest.mark.parametrize("index", range(len(MIXED)))
def test_an_env_of_the_mix_plays_what_make_plays(played, index):
    in_mix, alone = played
    got = jax.tree.map(lambda leaf: leaf[index], in_mix)
    for want, have in zip(jax.tree.leaves(alone[index]), jax.tree.leaves(got)):
        np.testing.assert_array_equal(want, have)


@pytest.mark.slow  # steps each game's single env eagerly beside the batch (a minute); each game's own test above is fast
def test_one_batch_plays_every_game_at_once(mix):
    env, params = mix
    games = jnp.arange(len(MIXED))
    keys = jax.random.split(jax.random.key(9), len(MIXED))
    step = jax.jit(jax.vmap(env.step, in_axes=(0, 0, 0, None)))
    obs, state = jax.vmap(lambda k, g: env.reset(k, params, game=g))(keys, games)
    singles = [octax_core.make(game, **OPTIONS) for game in MIXED]
    single_states = [single.reset(keys[i], p)[1] for i, (single, p) in enumerate(singles)]
    for t in range(5):
        actions = jnp.array([t % single.num_actions for single, _ in singles])
        step_keys = jax.random.split(jax.random.key(100 + t), len(MIXED))
        obs, state, reward, terminated, truncated, info = step(step_keys, state, actions, params)
        np.testing.assert_array_equal(info["game"], games)
        for i, (single, p) in enumerate(singles):
            single_obs, single_states[i], single_reward, *_ = single.step(step_keys[i], single_states[i],
                                                                          actions[i], p)
            np.testing.assert_array_equal(obs[i], single_obs)
            assert float(reward[i]) == float(single_reward)


def test_reset_draws_games_by_weight_and_reports_them():
    env, params = octax_core.make_mix(["Pong", "Brix", "Tetris"], weights=[1, 0, 3])
    keys = jax.random.split(jax.random.key(0), 400)
    _, state = jax.jit(jax.vmap(env.reset, in_axes=(0, None)))(keys, params)  # one compile, not one per op
    counts = np.bincount(np.asarray(state.game), minlength=3)
    assert counts[1] == 0 and 60 < counts[0] < 140 and counts[0] + counts[2] == 400
    assert env.games == ("Pong", "Brix", "Tetris") and env.num_games == 3
    info = env.info(jax.tree.map(lambda leaf: leaf[0], state))
    assert set(info) >= {"game", "action_mask", "score", "lives", "episode_step"}


def test_the_action_space_is_the_largest_games_with_a_mask_per_game():
    env, params = octax_core.make_mix(["Pong", "Tetris", "Missile"])  # 2, 4 and 1 keys
    assert env.num_actions == 5
    masks = [np.asarray(env.info(env.reset(jax.random.key(0), params, game=g)[1])["action_mask"]) for g in range(3)]
    np.testing.assert_array_equal(masks, [[1, 1, 1, 0, 0], [1, 1, 1, 1, 1], [1, 1, 0, 0, 0]])
    # an action past the game's last holds no key: it plays as no-op
    _, state = env.reset(jax.random.key(0), params, game=2)
    past = env.step(jax.random.key(1), state, 4, params)
    noop = env.step(jax.random.key(1), state, 0, params)
    assert int(past[1].last_action) == 4  # what was asked, kept for sticky actions
    past = (past[0], past[1].replace(last_action=noop[1].last_action), *past[2:])
    for a, b in zip(jax.tree.leaves(past), jax.tree.leaves(noop)):
        np.testing.assert_array_equal(a, b)


def test_autoreset_starts_the_next_episode_on_a_drawn_game():
    env, params = octax_core.make_mix(["Pong", "Brix"], weights=[0, 1], autoreset=True, max_episode_steps=2)
    obs, state = env.reset(jax.random.key(0), params, game=0)
    step = jax.jit(env.step)
    for t in range(2):
        obs, state, reward, terminated, truncated, info = step(jax.random.key(t), state, 0, params)
    assert bool(truncated) and int(info["game"]) == 0 and int(state.game) == 1  # the new episode: Brix


def test_per_game_episode_lengths_are_params(mix):
    env, params = mix
    lengths = [octax_core.get_spec(game).max_episode_steps for game in MIXED]
    np.testing.assert_array_equal(params.max_episode_steps, lengths)
    _, short = octax_core.make_mix(["Pong", "Brix"], max_episode_steps=7)
    np.testing.assert_array_equal(short.max_episode_steps, [7, 7])


def test_bad_mixes_are_named_errors():
    with pytest.raises(ValueError, match=r"non-empty list of games or a named mix \(octax16\); valid ids: .*Pong"):
        octax_core.make_mix([])
    with pytest.raises(ValueError, match="non-empty list of games"):
        octax_core.make_mix("Pong")
    with pytest.raises(KeyError, match="unknown game 'Nope'"):
        octax_core.make_mix(["Pong", "Nope"])
    with pytest.raises(ValueError, match=r"one platform, got several \(chip8: Pong; schip: Rockto\)"):
        octax_core.make_mix(["Pong", "Rockto"])
    with pytest.raises(ValueError, match=r"weights must be one number per game \(2\)"):
        octax_core.make_mix(["Pong", "Brix"], weights=[1, 2, 3])
    with pytest.raises(ValueError, match="weights must be finite, >= 0 and not all 0"):
        octax_core.make_mix(["Pong", "Brix"], weights=[0, 0])
    with pytest.raises(TypeError, match="unknown keyword"):
        octax_core.make_mix(["Pong"], speed=3)
    env, params = octax_core.make_mix(["Pong", "Brix"])
    with pytest.raises(ValueError, match="game 2 is out of range; this mix's games are 0..1: 0 Pong, 1 Brix"):
        env.reset(jax.random.key(0), params, game=2)
    _, state = env.reset(jax.random.key(0), params, game=0)
    with pytest.raises(ValueError, match=r"action 3 is out of range; valid actions are 0..2"):
        env.step(jax.random.key(0), state, 3, params)


def test_a_users_game_spec_mixes_with_registered_ones(counter_rom):
    env, params = octax_core.make_mix([COUNTER, "Pong"], roms=[counter_rom, None])
    _, state = env.reset(jax.random.key(0), params, game=0)
    _, state, reward, *_ = env.step(jax.random.key(0), state, 1, params)
    single, single_params = octax_core.make(COUNTER, rom=counter_rom)
    _, single_state = single.reset(jax.random.key(0), single_params)
    _, _, single_reward, *_ = single.step(jax.random.key(0), single_state, 1, single_params)
    assert float(reward) == float(single_reward) == 4.0


def _switch_sizes(env, params) -> list[int]:
    """The number of branches of every `lax.switch`/`cond` in the traced step of `env`."""
    _, state = env.reset(jax.random.key(0), params, game=0)
    jaxpr = jax.make_jaxpr(lambda k, s: env.step(k, s, 1, params))(jax.random.key(1), state)
    sizes = []

    def walk(jaxpr):
        for eqn in jaxpr.eqns:
            if eqn.primitive.name == "cond":
                sizes.append(len(eqn.params["branches"]))
            for value in eqn.params.values():
                for item in value if isinstance(value, (tuple, list)) else (value,):
                    inner = getattr(item, "jaxpr", None)
                    if inner is not None:
                        walk(inner if hasattr(inner, "eqns") else inner.jaxpr)
    walk(jaxpr.jaxpr)
    return sizes


def test_games_that_share_their_functions_share_one_branch(counter_rom):
    """A generated family's variants share their score, end and lives functions (the ROM is data):
    the step switches over the distinct functions, so it does not grow with the number of games."""
    import dataclasses

    copies = [dataclasses.replace(COUNTER, id=f"Counter{i}") for i in range(3)]
    shared, shared_params = octax_core.make_mix(copies, roms=[counter_rom] * 3)
    assert 3 not in _switch_sizes(shared, shared_params)
    own_score = dataclasses.replace(copies[2], score_fn=lambda m: m.V[0].astype(jnp.int32) * 2)
    distinct, distinct_params = octax_core.make_mix([*copies[:2], own_score], roms=[counter_rom] * 3)
    # one more two-way switch than the shared mix has: the score's, over two distinct functions
    assert _switch_sizes(distinct, distinct_params).count(2) == _switch_sizes(shared, shared_params).count(2) + 1
    _, state = distinct.reset(jax.random.key(0), distinct_params, game=2)
    _, _, reward, *_ = distinct.step(jax.random.key(0), state, 1, distinct_params)
    _, state = distinct.reset(jax.random.key(0), distinct_params, game=0)
    _, _, reward0, *_ = distinct.step(jax.random.key(0), state, 1, distinct_params)
    assert float(reward) == 2 * float(reward0) == 8.0  # each game still reads its own function


def test_a_machine_of_profiles_needs_its_profile():
    machine = octax_core.Machine("chip8", profiles=(("chip8", 11), ("schip", 15)))
    assert machine.instructions_per_frame == 15 and machine.quirks == octax_core.QUIRK_PROFILES["chip8"]
    state = machine.boot(bytes([0x12, 0x00]), jax.random.key(0))
    with pytest.raises(ValueError, match="runs 2 profiles: give run_frames/execute profile=0..1"):
        machine.run_frames(state, 0, 1)
    with pytest.raises(ValueError, match="profile 2 is out of range; valid: 0..1"):
        machine.run_frames(state, 0, 1, profile=2)
    with pytest.raises(ValueError, match="profile= is for a Machine with profiles"):
        octax_core.Machine("chip8").run_frames(state, 0, 1, profile=0)
