"""Our own games, Dodge and Flak (roms/*.8o): every level starts, scores, ends and differs.

Random play runs on the bare `Machine` (one compile serves both games and all their levels: the
ROM is in the state, not the program), started from each spec's start-up and reseeded per env as
`Env.reset` does. Scripted policies that read the registers and the object tables show the
games are winnable far above random. Gymnasium's checker and seeding run on the plain ids.
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import gymnasium
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import octax_core
import octax_gym
from octax_core.env.games import get_spec
from octax_core.tools.octo import assemble_program
from octax_core.emulator.keypad import keys_to_mask
from octax_core.emulator.state import MEMORY_OFFSET, seed_rng
from octax_core.env.starts import _frames_runner

ROMS = Path(__file__).resolve().parents[2] / "roms"
LEVELS = {"Dodge": ("Dodge1", "Dodge2", "Dodge3"), "Flak": ("Flak1", "Flak2", "Flak3")}
ALL_IDS = [game_id for levels in LEVELS.values() for game_id in levels] + list(LEVELS)
FRAMES_PER_STEP = 4
NUM_ENVS = 32
STEPS = 2500  # every random episode of every level ends before this (longest seen: about 2,000)
MACHINE = octax_core.Machine("chip8", instructions_per_frame=11)


@functools.cache
def _labels(name: str) -> dict[str, int]:
    return assemble_program((ROMS / f"{name}.8o").read_text()).labels


@functools.cache
def _runner():
    """(states, masks (T, N)) -> per-step (score V5, lives V6, over VE); one compile for all."""
    def run(states, masks):
        def body(states, mask):
            states = jax.vmap(lambda s, m: MACHINE.run_frames(s, m, FRAMES_PER_STEP))(states, mask)
            return states, (states.V[:, 5], states.V[:, 6], states.V[:, 14])
        return jax.lax.scan(body, states, masks)
    return jax.jit(run)


def _start(game_id: str, seed: int = 0):
    """NUM_ENVS machines after the spec's start-up, each reseeded from its own key as reset does.
    The start-up runs on the frame runner `make` boots with (the frame count traced: one compile)."""
    spec = get_spec(game_id)
    state = MACHINE.boot(ROMS / spec.rom_file, jax.random.key(0))
    for mask, frames in spec.startup:
        state = _frames_runner(MACHINE)(state, keys_to_mask(mask), jnp.int32(frames))
    keys = jax.random.split(jax.random.key(seed), NUM_ENVS)
    return jax.vmap(lambda k: state.replace(rng=seed_rng(k)))(keys)


# The plain ids are their middle level's spec under another name (test_plain_ids_are_the_middle_level),
# so random play runs the levels only: every level's NUM_ENVS envs in one batch, one call.
LEVEL_IDS = [game_id for levels in LEVELS.values() for game_id in levels]


@functools.cache
def _random_play_all():
    states, masks = [], []
    for game_id in LEVEL_IDS:
        spec = get_spec(game_id)
        keys = np.array([0] + [1 << k for k in spec.action_keys], np.uint32)
        actions = np.random.default_rng(1).integers(0, len(keys), (STEPS, NUM_ENVS))
        states.append(_start(game_id))
        masks.append(keys[actions])
    states = jax.tree.map(lambda *leaves: jnp.concatenate(leaves), *states)
    _, out = _runner()(states, jnp.asarray(np.concatenate(masks, axis=1)))
    return tuple(np.asarray(x, int) for x in out)


def _random_play(game_id: str):
    """STEPS uniform random actions in NUM_ENVS envs: (score, lives, over), each (T, N) int."""
    game_id = {name: levels[1] for name, levels in LEVELS.items()}.get(game_id, game_id)
    envs = slice(LEVEL_IDS.index(game_id) * NUM_ENVS, (LEVEL_IDS.index(game_id) + 1) * NUM_ENVS)
    return tuple(x[:, envs] for x in _random_play_all())


def _episode_lengths(game_id: str) -> np.ndarray:
    over = _random_play(game_id)[2]
    assert over.any(axis=0).all(), f"{game_id}: some random episodes did not end in {STEPS} steps"
    return over.argmax(axis=0) + 1


def test_roms_are_the_specs_roms():
    for game_id in ALL_IDS:
        spec = get_spec(game_id)
        assert octax_core.Rom.load(ROMS / spec.rom_file).sha1 == spec.rom_sha1
        assert spec.quirks == "chip8" and spec.terminated_fn is not None


@pytest.mark.parametrize("game_id", ALL_IDS)
def test_startup_stops_in_the_pause_before_play(game_id):
    """Start-up ends with the play screen drawn and no object placed yet, so each episode's
    objects come from its own reset key."""
    name = get_spec(game_id).rom_file.removesuffix(".ch8")
    state = _start(game_id)
    V = np.asarray(state.V[0]).astype(int)
    table = _labels(name)["rocks" if name == "dodge" else "planes"]
    assert (V[5], V[6], V[14]) == (0, 3, 0)
    assert not np.asarray(state.memory[0, MEMORY_OFFSET + table:MEMORY_OFFSET + table + 9]).any()
    assert int(state.delay_timer[0]) > 0, "start-up ran past the pause"
    level = int(get_spec(game_id).title.split("level ")[1][0])
    if name == "dodge":
        assert V[8] == level


@pytest.mark.parametrize("game_id", LEVEL_IDS)
def test_random_play_scores_and_ends(game_id):
    score, lives, over = _random_play(game_id)
    ends = _episode_lengths(game_id)
    assert 100 < ends.mean() < 1500, f"{game_id}: mean random episode {ends.mean():.0f} steps"
    for i, end in enumerate(ends):
        assert lives[end - 1, i] == 0 and over[end:, i].all(), "the game ended otherwise, or restarted"
        assert (np.diff(score[:end, i]) >= 0).all() and (np.diff(score[:end, i]) <= 1).all()
        assert score[end:, i].max() == score[end - 1, i], "the score moved after the game ended"
    assert (score[ends - 1, np.arange(NUM_ENVS)] > 0).mean() > 0.8


@pytest.mark.parametrize("name", list(LEVELS))
def test_harder_levels_end_sooner_at_random(name):
    means = [_episode_lengths(game_id).mean() for game_id in LEVELS[name]]
    assert means[0] > means[1] > means[2], f"{name}: mean random episode lengths {means}"


def test_plain_ids_are_the_middle_level():
    """Everything but the id is the middle level's: the same ROM, start-up, keys and rules, so
    the plain id plays what its middle level plays (random play runs the levels)."""
    for name, levels in LEVELS.items():
        plain, middle = get_spec(name), get_spec(levels[1])
        for field in dataclasses.fields(plain):
            a, b = getattr(plain, field.name), getattr(middle, field.name)
            if field.name != "id" and not callable(a):
                assert a == b, (name, field.name, a, b)
        start = jax.tree.map(lambda x: x[0], _start(levels[1]))
        for rule in ("score_fn", "terminated_fn", "lives_fn"):
            a, b = getattr(plain, rule, None), getattr(middle, rule, None)
            assert (a is None) == (b is None), rule
            if a is not None:
                np.testing.assert_array_equal(a(start), b(start), err_msg=f"{name}: {rule}")


# --- scripted policies: the games are winnable ------------------------------------------------


def _dodge_policy(labels):
    """Step away from the lowest rock above the ship (1: left, 2: right), else wait."""
    def policy(machine):
        rocks = jax.lax.dynamic_slice(machine.memory, (MEMORY_OFFSET + labels["rocks"],), (8,))
        rocks = rocks.astype(jnp.int32).reshape(4, 2)
        ship = machine.V[3].astype(jnp.int32)
        near = rocks[:, 0] + 3 - ship
        danger = (jnp.arange(4) < machine.V[9] // 2) & (near >= -2) & (near <= 10) & (rocks[:, 1] >= 12)
        rock = jnp.argmax(jnp.where(danger, rocks[:, 1], -1))
        left = jnp.where(ship <= 4, False, jnp.where(ship >= 54, True, rocks[rock, 0] + 2 >= ship + 3))
        return jnp.where(danger.any(), jnp.where(left, 1, 2), 0)
    return policy


def _flak_policy(labels):
    """Move under the nearest plane's lead point (1: left, 2: right), then fire (3)."""
    def policy(machine):
        planes = jax.lax.dynamic_slice(machine.memory, (MEMORY_OFFSET + labels["planes"],), (9,))
        planes = planes.astype(jnp.int32).reshape(3, 3)
        count = machine.V[8].astype(jnp.int32) // 3
        gun = machine.V[3].astype(jnp.int32) + 2
        # the shell climbs 4 rows per plane moved, a plane flies V4 pixels per round of `count` moves
        lead = (24 - planes[:, 1]) // 4 * machine.V[4].astype(jnp.int32) // jnp.maximum(count, 1)
        target = planes[:, 0] + 3 + jnp.where(planes[:, 2] == 0, lead, -lead)
        reachable = (jnp.arange(3) < count) & (target >= 2) & (target <= 60)
        target = target[jnp.argmin(jnp.where(reachable, jnp.abs(target - gun), 999))]
        aimed = jnp.abs(target - gun) <= 1
        return jnp.where(aimed, jnp.where(machine.V[10] == 0, 3, 0), jnp.where(target < gun, 1, 2))
    return policy


@functools.cache
def _scripted_scores(steps: int):
    """Dodge3's and Flak3's scripted policies, NUM_ENVS envs each, in one program: the scores after
    `steps` steps, {game_id: (NUM_ENVS,) int}."""
    games = ["Dodge3", "Flak3"]
    policies = [_dodge_policy(_labels("dodge")), _flak_policy(_labels("flak"))]
    width = max(len(get_spec(g).action_keys) for g in games) + 1
    masks = jnp.array([([0] + [1 << k for k in get_spec(g).action_keys] + [0] * width)[:width] for g in games],
                      jnp.uint32)
    which = jnp.repeat(jnp.arange(2), NUM_ENVS)

    @jax.jit
    def run(states):
        def body(states, _):
            actions = jax.vmap(lambda g, m: jax.lax.switch(g, policies, m))(which, states)
            states = jax.vmap(lambda s, m: MACHINE.run_frames(s, m, FRAMES_PER_STEP))(states, masks[which, actions])
            return states, states.V[:, 5]
        return jax.lax.scan(body, states, None, length=steps)[1]

    starts = jax.tree.map(lambda *leaves: jnp.concatenate(leaves), *(_start(g) for g in games))
    last = np.asarray(run(starts))[-1].astype(int)
    return {g: last[i * NUM_ENVS:(i + 1) * NUM_ENVS] for i, g in enumerate(games)}


@pytest.mark.parametrize("game_id", ["Dodge3", "Flak3"])
def test_scripted_policy_beats_random(game_id):
    steps = 600
    scripted = _scripted_scores(steps)[game_id]
    random_score = _random_play(game_id)[0]
    random_at = random_score[np.minimum(steps, _episode_lengths(game_id)) - 1, np.arange(NUM_ENVS)]
    assert scripted.mean() > 3 * random_at.mean(), (scripted.mean(), random_at.mean())


# --- through Gymnasium ------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["Dodge", pytest.param("Flak", marks=pytest.mark.slow)])  # the same check
def test_gymnasium_make_passes_the_checker_and_seeds(name):
    gymnasium.register_envs(octax_gym)
    env = gymnasium.make(f"octax/{name}-v0")
    check_env(env.unwrapped)
    actions = np.random.default_rng(0).integers(0, env.action_space.n, 60)

    def play(seed):
        obs, _ = env.reset(seed=seed)
        frames = [obs]
        for action in actions:
            frames.append(env.step(int(action))[0])
        return np.stack(frames)

    first = play(7)
    assert np.array_equal(first, play(7)), "same seed, different episode"
    assert not np.array_equal(first, play(8)), "different seeds, same episode"
    env.close()
