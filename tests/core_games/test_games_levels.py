"""Per-level checks of the multi-level families: Cavern (7), Space Flight (10), Target Shooter (3).

Levels of a family share their code and differ only in data bytes, so every level gets the
cheap checks on the bare `Machine`, driven by its spec (start-up reaches play, the score moves,
the game ends within a stated bound), and one level per family the env-API checks (a scripted
episode, a random policy over 16 envs). JAX compiles dominate the cost: one machine runner for
all levels, and one batched env for the three families' env tests (a mix), each built once.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.env.games import get_spec

from game_harness import PinnedMix

CAVERN = [f"Cavern{level}" for level in range(1, 8)]
SPACE_FLIGHT = [f"SpaceFlight{level}" for level in range(1, 11)]
TARGET_SHOOTER = [f"TargetShooter{level}" for level in range(1, 4)]
FRAMES_PER_STEP = 4
NUM_ENVS = 16

# Found by a beam search over (no-op, up, down) on SpaceFlight1's field, which start-up draws
# from the boot key 0: crosses without a collision in 53 steps.
SPACE_FLIGHT1_CROSSING = "...^.^.^.^^.^.^.^^.^.^.^^.^.^.^^.^.^.^^.^.^.^^.^.^...."
# The same crossing in 5-frame steps (each move's key moved to the step that holds it at the move).
SPACE_FLIGHT1_CROSSING_5 = "...^^^.^^.^^^.^^.^^^.^^.^^^.^^.^^^.^^.^^....."
SPACE_FLIGHT_EDGE = (212, 213)  # the frames after start-up at which VC == 0x3E, at every level


@functools.cache
def _runner(machine: octax_core.Machine):
    """(state, key mask, frames) -> state with the frame count traced: one compile per machine."""
    def run(state, mask, frames):
        return jax.lax.fori_loop(0, frames, lambda _, s: machine.run_frames(s, mask, 1), state)
    return jax.jit(run)


def _start(game_id: str, rom_dir):
    """The spec's machine booted as `make` does (key 0) and run through the spec's start-up."""
    spec = get_spec(game_id)
    machine = octax_core.Machine(quirks=spec.quirks, instructions_per_frame=11)
    state = machine.boot(rom_dir / spec.rom_file, jax.random.key(0))
    for mask, frames in spec.startup:
        state = _runner(machine)(state, mask, frames)
    return spec, machine, state


def _mask(spec, action: int) -> int:
    return 0 if action == 0 else 1 << spec.action_keys[action - 1]


def _play(spec, machine, state, policy, max_steps: int):
    """Env-like steps (4 frames, policy(V) -> action) until the spec says the game is over.

    Returns:
        (steps taken or None if the game did not end, score gained, final state).
    """
    run, start = _runner(machine), int(spec.score_fn(state))
    for step in range(1, max_steps + 1):
        state = run(state, _mask(spec, policy(np.asarray(state.V))), FRAMES_PER_STEP)
        if bool(spec.terminated_fn(state)):
            return step, int(spec.score_fn(state)) - start, state
    return None, int(spec.score_fn(state)) - start, state


def _aim(V) -> np.ndarray:
    """Target Shooter oracle over V (..., 16): step toward the target (V4, V5), shoot when close."""
    dx = V[..., 4].astype(int) - V[..., 0].astype(int)
    dy = V[..., 5].astype(int) - V[..., 1].astype(int)
    # actions: 1 up, 2 left, 3 down, 4 right, 5 shoot (a hit needs centres within 6 pixels)
    return np.select([dx < -3, dx > 3, dy < -3, dy > 3], [2, 4, 1, 3], 5)


def _lit(state) -> int:
    return int(octax_core.snapshot(state)["screen"].sum())


# --- every level: start-up, score, ending ---------------------------------------------------


@pytest.mark.parametrize("game_id", CAVERN + SPACE_FLIGHT + TARGET_SHOOTER)
def test_rom_hash_matches_spec(game_id, octax_rom_dir):
    spec = get_spec(game_id)
    assert octax_core.Rom.load(octax_rom_dir / spec.rom_file).sha1 == spec.rom_sha1


@pytest.mark.parametrize("game_id", CAVERN)
def test_cavern_startup_then_hold_left_scores_and_crashes(game_id, octax_rom_dir):
    spec, machine, state = _start(game_id, octax_rom_dir)
    screen = octax_core.snapshot(state)["screen"]
    assert screen[31].all(), "start-up ended before the maze's last tile row was drawn"
    assert int(state.V[14]) == 1
    waited = _runner(machine)(state, 0, 20 * FRAMES_PER_STEP)
    assert (int(waited.V[3]), int(waited.V[4])) == (int(state.V[3]), int(state.V[4])), "the dot moved unbidden"
    steps, gained, _ = _play(spec, machine, state, lambda V: 2, max_steps=80)  # 2: key 4, left
    assert steps is not None, "holding left did not hit a wall within 80 steps"
    assert gained >= 9, f"only {gained} new leftmost columns before the crash"


@pytest.mark.parametrize("game_id", SPACE_FLIGHT)
def test_space_flight_startup_then_noop_scores_and_crashes(game_id, octax_rom_dir):
    spec, machine, state = _start(game_id, octax_rom_dir)
    assert int(state.V[3]) == 0xFF, "start-up ended before every asteroid was drawn"
    assert int(state.V[12]) == 0, "the ship moved during start-up"
    assert int(_runner(machine)(state, 0, FRAMES_PER_STEP).V[12]) == 2, "the ship's first move is not in step 1"
    steps, gained, final = _play(spec, machine, state, lambda V: 0, max_steps=12)
    assert steps is not None and int(final.V[9]) == 0, "flying straight did not crash within 12 steps"
    assert gained >= 3


@pytest.mark.parametrize("game_id", TARGET_SHOOTER)
def test_target_shooter_startup_then_aiming_scores_and_ends(game_id, octax_rom_dir):
    spec, machine, state = _start(game_id, octax_rom_dir)
    assert _lit(state) == 24 and int(state.V[6]) == 0, "start-up should leave just the crosshair"
    lit = []
    for _ in range(FRAMES_PER_STEP):  # level 3's moving target is missing from ~1 frame in 4
        state = _runner(machine)(state, 0, 1)
        lit.append(_lit(state))
    assert int(state.V[6]) == 1 and max(lit) > 24, f"no target in the first step: {lit} pixels lit"
    steps, gained, _ = _play(spec, machine, state, lambda V: int(_aim(V)), max_steps=400)
    assert steps is not None, "the aiming policy did not end the game within 400 steps"
    assert gained == 10 if game_id == "TargetShooter1" else 8 <= gained <= 9, gained


@pytest.mark.parametrize("game_id, bound", [("TargetShooter2", 700), ("TargetShooter3", 1700)])
def test_target_shooter_timeouts_end_the_game(game_id, bound, octax_rom_dir):
    spec, machine, state = _start(game_id, octax_rom_dir)
    steps, gained, final = _play(spec, machine, state, lambda V: 0, max_steps=bound)
    assert steps is not None, f"10 targets did not time out within {bound} no-op steps"
    assert gained == 0 and int(final.V[10]) == 10
    assert steps < spec.max_episode_steps


def test_space_flight_crossing_is_a_2_frame_window(octax_rom_dir):
    """The paper's rule sees a crossing only while VC >= 0x3E, 2 frames, before the ROM starts
    the ship on a new field: a 4-frame step ends in them, a 5-frame step straddles them."""
    spec, machine, state = _start("SpaceFlight1", octax_rom_dir)
    run, frames = _runner(machine), []
    for action in SPACE_FLIGHT1_CROSSING:  # 216 frames: the crossing and 3 frames of the next field
        for _ in range(FRAMES_PER_STEP):
            state = run(state, _mask(spec, ".^v".index(action)), 1)
            frames.append((bool(spec.terminated_fn(state)), int(state.V[9]), int(state.V[10])))
    ended = tuple(i for i, (done, _, _) in enumerate(frames, 1) if done)
    assert ended == SPACE_FLIGHT_EDGE, f"the paper's rule held at frames {ended}"
    assert frames[-1] == (False, 1, 3), "after the window: no collision, one crossing counted, not terminated"
    assert SPACE_FLIGHT_EDGE[0] % FRAMES_PER_STEP == 0, "with 4-frame steps the paper's test sees the edge"
    assert not any(frame % 5 == 0 for frame in ended), "with 5-frame steps the paper's test misses it"


@pytest.mark.parametrize("game_id", SPACE_FLIGHT)
def test_space_flight_every_level_crosses_at_the_same_frames(game_id, octax_rom_dir):
    """With the asteroids wiped (only x < 8, the ship, kept) every level crosses at frames 212-213,
    which 4-frame steps always see: the paper's rule ends a 4-frame crossing on step 53."""
    spec, machine, state = _start(game_id, octax_rom_dir)
    state = state.replace(screen=state.screen & np.array([0xFF000000, 0], np.uint32))
    run = _runner(machine)
    state = run(state, 0, SPACE_FLIGHT_EDGE[0] - 1)
    flags = []
    for _ in range(3):
        flags.append(bool(spec.terminated_fn(state)))
        state = run(state, 0, 1)
    flags.append(bool(spec.terminated_fn(state)))
    assert flags == [False, True, True, False], f"the paper's rule over frames 211-214: {flags}"
    assert (int(state.V[9]), int(state.V[10]), int(state.V[12])) == (1, 3, 0), "not on a new field"


# --- one level per family through the env API -----------------------------------------------


# The env tests' three games, level 1 of each family, in one mix (`octax_core.make_mix`, the game
# as data: one compiled step for the three) with autoreset, NUM_ENVS envs per game. `PinnedMix`
# (game_harness) restarts an ended episode on its env's own game, as `make(game)`'s autoreset does,
# and env g * NUM_ENVS + i is reset and stepped with the keys of `make(ENV_GAMES[g])`'s env i, so
# each game's envs play exactly what `make(game, autoreset=True)` plays (the mix's exactness:
# tests/core_env/test_mix.py).
ENV_GAMES = ["Cavern1", "SpaceFlight1", "TargetShooter1"]


@functools.cache
def _batched_env(rom_dir):
    """The mix with its jitted batched reset and step, shared by this module's env tests."""
    specs = [get_spec(game_id) for game_id in ENV_GAMES]
    env = PinnedMix(specs, None, dict(autoreset=True), [rom_dir / spec.rom_file for spec in specs])
    params = env.default_params
    games = jnp.repeat(jnp.arange(len(ENV_GAMES), dtype=jnp.int32), NUM_ENVS)
    reset = jax.jit(jax.vmap(lambda key, game: env.reset(key, params, game=game)))
    step = jax.jit(jax.vmap(env.step, in_axes=(0, 0, 0, None)))
    return env, params, lambda keys: reset(keys, games), step


def _envs(game_id: str) -> slice:
    """The mix's envs that play `game_id`."""
    g = ENV_GAMES.index(game_id)
    return slice(g * NUM_ENVS, (g + 1) * NUM_ENVS)


def _each_game(keys):
    """Keys of NUM_ENVS envs (on the last axis) -> the same keys for every game of the mix."""
    return keys[..., np.tile(np.arange(NUM_ENVS), len(ENV_GAMES))]


def _episode(game_id, rom_dir, policy, max_steps: int, seed: int = 0):
    """Runs the game's NUM_ENVS envs with actions policy(V, episode_step) (the registers (N, 16)
    and episode steps (N,) of its envs) until each has ended once; the mix's other envs hold no key.

    Returns:
        (step at which each env first ended (0: never), return up to then, first reset obs).
    """
    _, params, reset, step = _batched_env(rom_dir)
    envs = _envs(game_id)
    obs, state = reset(_each_game(jax.random.split(jax.random.key(seed), NUM_ENVS)))
    first_obs, ended_at, returns = np.asarray(obs[envs]), np.zeros(NUM_ENVS, int), np.zeros(NUM_ENVS)
    keys = _each_game(jax.random.split(jax.random.key(seed + 1), (max_steps, NUM_ENVS)))
    actions = np.zeros(len(ENV_GAMES) * NUM_ENVS, np.int32)
    for t in range(max_steps):
        actions[envs] = policy(np.asarray(state.machine.V[envs]), np.asarray(state.episode_step[envs]))
        obs, state, reward, terminated, truncated, _ = step(keys[t], state, actions, params)
        live = ended_at == 0
        returns += np.where(live, np.asarray(reward[envs]), 0.0)
        ended_at[live & np.asarray((terminated | truncated)[envs])] = t + 1
        if ended_at.all():
            break
    return ended_at, returns, first_obs


def _cavern1_escape(V, episode_step) -> int:
    """From (52, 20): up to row 3, left to column 18, down to row 27, then left out of the cave."""
    x, y = int(V[0, 3]), int(V[0, 4])
    if x >= 40 and y > 3:
        return 1  # key 2, up
    if x <= 18 and 5 < x and y < 27:
        return 4  # key 8, down
    return 2  # key 4, left


def test_env_cavern1_waits_then_crashes_left_and_escape_scores_max(octax_rom_dir):
    hold_left_from = 30
    ended_at, returns, obs = _episode(
        "Cavern1", octax_rom_dir, lambda V, episode_step: 2 if episode_step[0] >= hold_left_from else 0, 100)
    assert obs.shape == (NUM_ENVS, FRAMES_PER_STEP, 32, 64) and obs[0, -1, 31].all()
    assert (ended_at == hold_left_from + 12).all(), ended_at  # 12 steps of "left" from (52, 20)
    assert (returns == 9).all(), returns
    # Escaping scores the start column, 52; the wrap to the right edge then lands in a wall.
    ended_at, returns, _ = _episode("Cavern1", octax_rom_dir, _cavern1_escape, 200)
    assert (ended_at == 118).all() and (returns == 52).all(), (ended_at, returns)


def test_env_space_flight1_crossing_and_crash(octax_rom_dir):
    crossing = lambda V, episode_step: ".^v".index(SPACE_FLIGHT1_CROSSING[min(int(episode_step[0]), 53)])
    ended_at, returns, _ = _episode("SpaceFlight1", octax_rom_dir, crossing, 60)
    assert (ended_at == 53).all() and (returns == 30).all(), (ended_at, returns)
    ended_at, returns, _ = _episode("SpaceFlight1", octax_rom_dir, lambda V, episode_step: 0, 60)
    assert (ended_at == 10).all() and (returns == 5).all(), (ended_at, returns)


def test_env_space_flight1_at_5_frames_per_step_flies_past_the_crossing(octax_rom_dir):
    """With 5-frame steps the paper's rule misses the crossing (frames 212-213 fall in step 43):
    the episode runs on into a new field, where no-ops crash at its first move (step 56)."""
    env, params = octax_core.make("SpaceFlight1", rom=octax_rom_dir / "space_flight1.ch8", frames_per_step=5)
    actions = [".^v".index(a) for a in SPACE_FLIGHT1_CROSSING_5] + [0] * 15
    step = jax.jit(env.step)
    _, state = env.reset(jax.random.key(0), params)
    ended_at, rewards, crossings = None, [], []
    for t, action in enumerate(actions, 1):
        _, state, reward, terminated, truncated, _ = step(jax.random.key(t), state, action, params)
        rewards.append(float(reward))
        crossings.append(4 - int(state.machine.V[10]))  # VA counts the crossings down from 4
        if bool(terminated | truncated):
            ended_at = t
            break
    assert crossings[42] == 1 and crossings[41] == 0, "the ship did not cross in step 43"
    assert ended_at == 56 and int(state.machine.V[9]) == 0, (ended_at, int(state.machine.V[9]))
    assert sum(rewards) == 30 and not bool(truncated)


def test_env_target_shooter1_aiming_hits_ten(octax_rom_dir):
    ended_at, returns, _ = _episode(
        "TargetShooter1", octax_rom_dir, lambda V, episode_step: _aim(V), 300)
    assert ended_at.all() and (returns == 10).all(), (ended_at, returns)
    assert len(set(ended_at.tolist())) > 1, "every env saw the same targets: the reset key is not used"


@functools.cache
def _random_run(rom_dir):
    """1,500 uniform random steps of the mix's envs (each game's actions over its own, drawn as
    its own 16 envs would draw them): rewards (T, envs), episodes ended and truncated per env."""
    env, params, reset, step = _batched_env(rom_dir)
    steps = 1500
    _, state = reset(_each_game(jax.random.split(jax.random.key(7), NUM_ENVS)))
    actions = np.concatenate([np.random.default_rng(7).integers(0, len(get_spec(g).action_keys) + 1, (steps, NUM_ENVS),
                                                                dtype=np.int32) for g in ENV_GAMES], axis=1)
    keys = _each_game(jax.random.split(jax.random.key(8), (steps, NUM_ENVS)))
    rewards, endings, truncations = [], 0, 0
    for t in range(steps):
        _, state, reward, terminated, truncated, _ = step(keys[t], state, actions[t], params)
        rewards.append(reward)
        endings += np.asarray(terminated).astype(int)
        truncations += np.asarray(truncated).astype(int)
    return np.asarray(rewards), endings, truncations


@pytest.mark.parametrize("game_id, min_episodes", [("Cavern1", 100), ("SpaceFlight1", 500), ("TargetShooter1", 0)])
def test_env_random_policy(game_id, min_episodes, octax_rom_dir):
    """16 envs x 1,500 random steps: finite 0/1 rewards, and (but Target Shooter 1) many endings."""
    rewards, endings, truncations = _random_run(octax_rom_dir)
    envs = _envs(game_id)
    assert not truncations[envs].any()
    assert np.isfinite(rewards[:, envs]).all() and set(np.unique(rewards[:, envs])) <= {0.0, 1.0}
    assert endings[envs].sum() >= min_episodes, f"{game_id}: {endings[envs].sum()} episodes ended"
