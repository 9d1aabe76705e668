"""Third-party two-player games through `make_multi`: Space Racer and Tank! and Ultimate
Tic-tac-toe (Chip8 Community Archive, shipped) and Paddles (octax ROM set, from OCTAX_ROM_DIR).

Each seat's keys reach the machine as the ROM's source says; each seat's reward is its own
score's change, summing to zero where `zero_sum` is declared; in the turn-based games (Tank!,
Ultimate Tic-tac-toe) the turn passes after each move and the legal mask leaves the other seat
only no-op, so its keys never reach the machine; the scripted policies beat uniform random play
from either seat. One jitted rollout per (game, length): the per-step plan of both seats
(an action, `RANDOM` or `SCRIPTED`), every env's or each env's own, is an argument, NUM_ENVS
envs, episodes not reset once done. Random play's draws come from the host (numpy, one uniform
per seat and step, an argument too), so the program holds no random-number generator for them.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.emulator.state import MEMORY_OFFSET
from octax_core.env.games import paddles
from octax_core.env.games.archive import spaceracer, tankarchive, ultimatetictactoe

NUM_ENVS = 16
RANDOM, SCRIPTED = -1, -2  # plan entries; 0.. hold that action
GAMES = ["SpaceRacer", "TankArchive", "UltimateTicTacToe", "Paddles"]
NEW = ["TankArchive", "UltimateTicTacToe", "Paddles"]


def _probe(game_id: str, machine):
    """The numbers each test reads, per step."""
    V = machine.V.astype(jnp.int32)
    if game_id == "SpaceRacer":
        return jnp.stack([V[8], V[11], V[spaceracer.SCORE1], V[spaceracer.SCORE2]])
    if game_id == "Paddles":
        return jnp.stack([V[paddles.PADDLE_X[0]], V[paddles.PADDLE_X[1]], V[paddles.POINTS[0]], V[paddles.POINTS[1]]])
    if game_id == "TankArchive":
        ram = lambda address: machine.memory[MEMORY_OFFSET + address].astype(jnp.int32)
        return jnp.stack([ram(tankarchive.TURN), ram(tankarchive.SCORE[0]), ram(tankarchive.SCORE[1]),
                          V[tankarchive.POWER], V[tankarchive.ANGLE], machine.pc.astype(jnp.int32)])
    board = ultimatetictactoe.cells(machine)
    return jnp.stack([(board == 1).sum(), (board == 2).sum(), V[ultimatetictactoe.CURRENT_PLAYER],
                      machine.pc.astype(jnp.int32)])


@functools.cache
def _env(game_id: str):
    return octax_core.make_multi(game_id)


@functools.cache
def _rollout(game_id: str, steps: int):
    """(seed, plan (steps, 2)) -> rewards (T, N, 2), done (T, N), current_player (T, N), legal
    mask (T, N, 2, A) before each step, probe (T, N, k) after each step."""
    env, params = _env(game_id)
    policy = env.seats.scripted_policy or (lambda machine, seat: jnp.int32(0))  # SpaceRacer has none

    def one(key, plan, draws):
        reset_key, run_key = jax.random.split(key)
        _, state = env.reset(reset_key, params)

        def body(carry, inputs):
            state, done = carry
            step_key, wanted, draw = inputs
            mask = env.legal_action_mask(state)
            # uniform over each seat's legal actions: the draw in [0, 1) picks the k-th open one
            open_count = mask.sum(-1)
            k = jnp.minimum(jnp.floor(draw * open_count).astype(jnp.int32), open_count - 1)
            random_actions = jnp.argmax(jnp.cumsum(mask, -1) > k[:, None], -1)
            actions = jnp.stack([
                jnp.select([wanted[seat] == SCRIPTED, wanted[seat] == RANDOM],
                           [policy(state.machine, seat), random_actions[seat]], wanted[seat])
                for seat in range(2)]).astype(jnp.int32)
            _, new_state, rewards, terminated, truncated, _ = env.step_env(step_key, state, actions, params)
            new_state = jax.tree.map(lambda new, old: jnp.where(done, old, new), new_state, state)
            rewards = jnp.where(done, 0.0, rewards)
            out = (rewards, done | terminated | truncated, env.current_player(state), mask,
                   _probe(game_id, new_state.machine))
            return (new_state, out[1]), out

        return jax.lax.scan(body, (state, jnp.bool_(False)), (jax.random.split(run_key, steps), plan, draws))[1]

    run = jax.jit(jax.vmap(one, in_axes=(0, 1, 1)))

    def rollout(seed, plan):
        """`seed`: an int (env i resets from its own key, random play draws from numpy's seed)
        or one key, which every env resets from (random play from seed 0's draws);
        `plan`: (steps, 2), every env's, or (steps, NUM_ENVS, 2), each env's own."""
        keys = jax.random.split(jax.random.key(seed), NUM_ENVS) if isinstance(seed, int) else \
            jnp.stack([seed] * NUM_ENVS)
        draws = np.random.default_rng(seed if isinstance(seed, int) else 0).random((steps, NUM_ENVS, 2), np.float32)
        plan = jnp.broadcast_to(jnp.asarray(plan, jnp.int32).reshape(steps, -1, 2), (steps, NUM_ENVS, 2))
        return tuple(np.asarray(x).swapaxes(0, 1) for x in run(keys, plan, draws))
    return rollout


STEPS = {"SpaceRacer": 120, "TankArchive": 700, "UltimateTicTacToe": 1500, "Paddles": 1500}


@functools.cache
def _play(game_id: str, modes: tuple[int, int], seed: int = 0):
    steps = STEPS[game_id]
    return _rollout(game_id, steps)(seed, np.tile(np.array(modes), (steps, 1)))


@pytest.fixture(scope="module", autouse=True)
def _roms(octax_rom_dir):
    """Paddles' ROM is the octax set's (never committed)."""


# --- the registry -----------------------------------------------------------------------------------


def test_the_games_are_two_player_only():
    two = octax_core.list_games(players=2)
    assert set(GAMES) <= set(two)
    for game_id in NEW:
        spec = octax_core.get_spec(game_id)
        assert not spec.solo and game_id not in octax_core.list_games() and spec.seats.zero_sum
        with pytest.raises(ValueError):
            octax_core.make(game_id)
    assert octax_core.get_spec("SpaceRacer").solo and not octax_core.get_spec("SpaceRacer").seats.turn_based
    assert octax_core.get_spec("TankArchive").seats.turn_based
    assert octax_core.get_spec("UltimateTicTacToe").seats.turn_based
    assert not octax_core.get_spec("Paddles").seats.turn_based
    assert octax_core.env.suite_of("Paddles") == "octax" and octax_core.env.suite_of("TankArchive") == "archive"


def test_tank_power_table_is_what_the_flight_model_gives():
    for seat in (0, 1):
        for row, distance in enumerate(tankarchive.DISTANCES):
            for dy in (-16, -5, 0, 3, 16):
                assert tankarchive.power_for(seat, distance, dy) == tankarchive.POWER_TABLE[seat][row][dy + 16]


# --- each seat's keys ---------------------------------------------------------------------------------


def _plan(steps, first, then=(0, 0), switch=None):
    plan = np.tile(np.array(first), (steps, 1))
    if switch is not None:
        plan[switch:] = then
    return plan


def _variants(game_id: str, variants) -> np.ndarray:
    """The per-env plan that gives env j `variants[j]` (a plan (steps, 2)), no-ops to the rest."""
    plan = np.zeros((STEPS[game_id], NUM_ENVS, 2), np.int32)
    for j, variant in enumerate(variants):
        plan[:, j] = variant
    return plan


def test_space_racer_seat_keys_move_their_own_ship():
    """Env 0: seat 0 up then down; env 1: seat 1 the same; env 2: both up: all from one start."""
    steps = STEPS["SpaceRacer"]
    plan = _variants("SpaceRacer", [_plan(steps, (1, 0), (2, 0), switch=40), _plan(steps, (0, 1), (0, 2), switch=40),
                                    _plan(steps, (1, 1), (0, 0), switch=5)])
    probe = _rollout("SpaceRacer", steps)(jax.random.key(0), plan)[4]
    ship1, ship2 = 0, 1
    for seat in (0, 1):
        own, other = probe[:, seat, (ship1, ship2)[seat]], probe[:, seat, (ship2, ship1)[seat]]
        assert (other == other[0]).all(), f"seat {seat}'s keys moved the other ship"
        assert own[:40].min() < own[0], f"seat {seat}'s up key (4 / D) did not raise its ship"
        assert own[-1] > own[40], f"seat {seat}'s down key (7 / E) did not lower its ship"
    # both seats at once: each ship where its own seat alone put it (5 steps up, no collision yet)
    assert probe[4, 2, ship1] == probe[4, 0, ship1] < probe[0, 2, ship1]
    assert probe[4, 2, ship2] == probe[4, 1, ship2] < probe[0, 2, ship2]


def test_paddles_seat_keys_move_their_own_paddle():
    """Env 0: seat 0 left then right; env 1: seat 1 the same; from one start."""
    steps = STEPS["Paddles"]
    plan = _variants("Paddles", [_plan(steps, (1, 0), (2, 0), switch=20), _plan(steps, (0, 1), (0, 2), switch=20)])
    probe = _rollout("Paddles", steps)(jax.random.key(0), plan)[4][:40]
    for seat in (0, 1):
        own, other = probe[:, seat, seat], probe[:, seat, 1 - seat]
        assert (other == 32).all(), f"seat {seat}'s keys moved the other paddle"
        assert (np.diff(own[:20]) <= 0).all() and own[19] <= 20, own  # keys 4 / 7: left, 2 pixels a pass
        assert (np.diff(own[20:]) >= 0).all() and own[-1] > own[19] + 10, own  # keys 6 / 9: right


def test_tank_closed_keys_never_reach_the_machine():
    """Seat 1 holds power + (key 5) all along, seat 0 nothing: the power moves only on seat 1's turns."""
    steps = STEPS["TankArchive"]
    rewards, done, mover, mask, probe = _rollout("TankArchive", steps)(1, _plan(steps, (0, 1)))
    power, pc = probe[..., 3], probe[..., 5]
    aiming = (pc >= tankarchive.AIM[0]) & (pc < tankarchive.AIM[1])
    rises = (np.diff(power, axis=0) > 0) & aiming[1:] & aiming[:-1]
    assert rises.any()
    assert (mover[1:][rises] == 1).all()
    assert (mover == 0).any() and (mover == 1).any()


def test_tank_turns_alternate_and_the_mask_follows_them():
    rewards, done, mover, mask, probe = _play("TankArchive", (SCRIPTED, SCRIPTED))
    turn = probe[..., 0]
    np.testing.assert_array_equal(mover[1:], 1 - (turn[:-1] & 1))  # the seat to move before step t + 1
    step = np.diff(turn, axis=0)[np.diff(turn, axis=0) != 0]
    new_round = turn[1:][np.diff(turn, axis=0) != 0] <= 1  # after a hit: a new hill, `turn := random 1`
    assert ((step == 1) | new_round).all() and (step == 1).sum() >= NUM_ENVS  # a miss passes the turn
    _check_mask(mover, mask)


def _check_mask(mover, mask):
    seats = np.arange(2)[None, None, :]
    is_mover = seats == mover[..., None]
    assert (mask[..., 0]).all()
    assert (~mask[..., 1:][~is_mover]).all(), "the seat not to move has an action besides no-op"
    assert mask[..., 1:][is_mover].any()


def test_tic_tac_toe_marks_alternate_and_the_mask_follows_the_turn():
    rewards, done, mover, mask, probe = _play("UltimateTicTacToe", (SCRIPTED, RANDOM))
    marks, current = probe[..., :2], probe[..., 2]
    np.testing.assert_array_equal(mover[1:], current[:-1])
    assert (mover[0] == 0).all(), "X moves first"
    for i in range(NUM_ENVS):
        flips = np.flatnonzero(current[1:, i] != current[:-1, i]) + 1
        assert len(flips) >= 8
        # the marks after each step, 0 before the first; row t + 3: after step t
        before = np.concatenate([np.zeros((3, 2), int), marks[:, i]])
        for t in flips:  # the mark is drawn a few instructions before the turn passes: this step or the last
            seat = current[t - 1, i]
            # the moving cursor (drawn by XOR) can read as a mark on a step before the move: the
            # marks after step t exceed the fewest after steps t-4..t-2
            assert before[t + 3, seat] > before[max(t - 1, 0):t + 2, seat].min(), (i, t)
    _check_mask(mover, mask)


def test_tic_tac_toe_place_closes_on_a_taken_cell():
    """X places in the middle of the middle board, which sends O there: its cursor is on X's mark."""
    plan = _plan(40, (5, 0), (0, 0), switch=1)  # X: key 6 one step, then released
    rewards, done, mover, mask, probe = _rollout("UltimateTicTacToe", STEPS["UltimateTicTacToe"])(0, np.concatenate(
        [plan, np.zeros((STEPS["UltimateTicTacToe"] - 40, 2), int)]))
    assert mover[0, 0] == 0 and mask[0, 0, 0].all() and not mask[0, 0, 1, 1:].any()
    assert probe[-1, 0, 0] == 1 and probe[-1, 0, 1] == 0 and mover[-1, 0] == 1
    np.testing.assert_array_equal(mask[-1, 0, 1], [True, True, True, True, True, False])
    np.testing.assert_array_equal(mask[-1, 0, 0], [True, False, False, False, False, False])


# --- rewards ------------------------------------------------------------------------------------------


def test_space_racer_rewards_are_each_ships_crossings():
    rewards, done, mover, mask, probe = _play("SpaceRacer", (1, 1))  # both fly up all along
    scores = np.concatenate([np.zeros((1, NUM_ENVS, 2), int), probe[..., 2:4]])
    np.testing.assert_array_equal(rewards, np.diff(scores, axis=0))
    assert (mover == -1).all() and mask.all()


@pytest.mark.parametrize("game_id", NEW)
def test_rewards_are_the_lead_and_zero_sum(game_id):
    rewards, done, mover, mask, probe = _play(game_id, (SCRIPTED, RANDOM))
    np.testing.assert_array_equal(rewards.sum(-1), 0)
    assert set(np.unique(rewards)) <= {-1.0, 0.0, 1.0} and (rewards != 0).any()
    if game_id != "UltimateTicTacToe":  # the points the ROM keeps: the lead's change
        a, b = (1, 2) if game_id == "TankArchive" else (2, 3)
        lead = probe[..., a] - probe[..., b]
        np.testing.assert_array_equal(rewards[..., 0], np.diff(np.concatenate([np.zeros((1, NUM_ENVS)), lead]), axis=0))
    else:  # one +-1 at the end of a won game
        assert (np.abs(rewards).sum(0)[:, 0] <= 1).all()
        assert (np.abs(rewards).sum(0)[:, 0][done[-1]] == 1).mean() > 0.5


# --- the scripted policy beats random -------------------------------------------------------------------


@pytest.mark.parametrize("game_id", NEW)
def test_scripted_policy_beats_random_from_either_seat(game_id):
    for seat, modes in ((0, (SCRIPTED, RANDOM)), (1, (RANDOM, SCRIPTED))):
        rewards, done, *_ = _play(game_id, modes)
        returns = rewards.sum(0)[:, seat]
        assert (returns > 0).mean() >= 0.5 and (returns < 0).mean() <= 0.1, (game_id, seat, returns)
        assert returns.mean() > 0.5 * WIN[game_id], (game_id, seat, returns)


WIN = {"TankArchive": tankarchive.HITS_TO_WIN, "UltimateTicTacToe": 1, "Paddles": paddles.POINTS_TO_WIN}
