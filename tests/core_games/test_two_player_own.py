"""Our own two-player games, Duel and Cycles (roms/duel.8o, roms/cycles.8o), through `make_multi`.

Each seat's keys move its own side only; each seat's reward is its own score's change, and the
two sum to zero; the scripted policies (`Seats.scripted_policy`) beat uniform random play from
either seat; episodes end. Cycles' two halves mirror each other exactly: the mirrored actions
give the mirrored game. One jitted rollout per game (each env's per-step plan of both seats, an
action, RANDOM or SCRIPTED, is an argument), 16 envs, one program for all of Cycles' levels;
Cycles2 (a speed between Cycles1's and Cycles3's) in make test-slow.
That the committed ROMs are what the sources build is tests/core_tools/test_own_roms.py's (it
globs roms/*.8o).
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.env.games import cycles, duel

GAMES = ["Duel", "Cycles1", "Cycles2", "Cycles3"]
# Cycles' levels differ in speed only: make test plays the slowest and the fastest, test-slow all.
FAST = ["Duel", "Cycles1", "Cycles3"]
GAME_PARAMS = [g if g in FAST else pytest.param(g, marks=pytest.mark.slow) for g in GAMES]
NUM_ENVS = 16
RANDOM, SCRIPTED, NOOP = -1, -2, 0  # plan entries; NOOP (0) and up: hold that action


@functools.cache
def _env(game_id: str):
    return octax_core.make_multi(game_id)


@functools.cache
def _rollout(game_id: str, steps: int):
    """(seed, plan (steps, NUM_ENVS, 2)) -> per-step rewards (T, N, 2), done (T, N), V (T, N, 16),
    for NUM_ENVS envs; a plan entry is RANDOM, SCRIPTED or an action (NOOP = 0). Episodes are not
    reset once done. The tests that drive seats by hand use it too. RANDOM's actions are drawn on
    the host (an argument), so the program holds no random-number generator for them.

    The reset is a small program of its own, and the rollout takes the start states, params and
    keys as arguments: it holds no level's data (the start states carry the level), so Cycles'
    levels, the same code, share one compiled rollout."""
    env, params = _env(game_id)
    policy = env.seats.scripted_policy

    def one(state, run_key, plan, random_actions, params):
        def body(carry, inputs):
            state, done = carry
            step_key, wanted, random_actions = inputs
            actions = jnp.stack([
                jnp.select([wanted[seat] == SCRIPTED, wanted[seat] == RANDOM],
                           [policy(state.machine, seat), random_actions[seat]], wanted[seat])
                for seat in range(2)]).astype(jnp.int32)
            _, new_state, rewards, terminated, truncated, _ = env.step_env(step_key, state, actions, params)
            new_state = jax.tree.map(lambda new, old: jnp.where(done, old, new), new_state, state)
            rewards = jnp.where(done, 0.0, rewards)
            done = done | terminated | truncated
            return (new_state, done), (rewards, done, new_state.machine.V)

        return jax.lax.scan(body, (state, jnp.bool_(False)), (jax.random.split(run_key, steps), plan, random_actions))[1]

    reset = jax.jit(jax.vmap(env.reset, in_axes=(0, None)))
    run = jax.jit(jax.vmap(one, in_axes=(0, 0, 1, 1, None)))

    def rollout(seed, plan):
        """`seed`: an int (env i resets from its own key; random play's actions are numpy's draws
        from that seed) or one key, which every env resets from (random actions from seed 0)."""
        keys = jax.random.split(jax.random.key(seed), NUM_ENVS) if isinstance(seed, int) else \
            jnp.stack([seed] * NUM_ENVS)
        random_actions = np.random.default_rng(seed if isinstance(seed, int) else 0).integers(
            0, env.num_actions, (steps, NUM_ENVS, 2), np.int32)
        split = jax.vmap(jax.random.split)(keys)
        reset_keys, run_keys = split[:, 0], split[:, 1]
        _, state = reset(reset_keys, params)
        return tuple(np.asarray(x).swapaxes(0, 1) for x in run(state, run_keys, jnp.asarray(plan, jnp.int32), random_actions, params))
    return rollout


STEPS = {"Duel": 900, "Cycles1": 600, "Cycles2": 600, "Cycles3": 600}


def _hold(game_id: str, modes) -> np.ndarray:
    """The plan that holds `modes` (one entry per seat) in every env at every step."""
    return np.broadcast_to(np.array(modes), (STEPS[game_id], NUM_ENVS, 2))


@functools.cache
def _play(game_id: str, modes: tuple[int, int], seed: int = 0):
    return _rollout(game_id, STEPS[game_id])(seed, _hold(game_id, modes))


def test_the_two_player_games_are_listed_and_solo():
    two = octax_core.list_games(players=2)
    for game_id in GAMES + ["Cycles"]:
        spec = octax_core.get_spec(game_id)
        assert game_id in two and game_id in octax_core.list_games(suite="ours")
        assert spec.solo and spec.seats.zero_sum and spec.action_keys == spec.seats.action_keys[0]
        assert not set(spec.seats.action_keys[0]) & set(spec.seats.action_keys[1])
    assert octax_core.get_spec("Cycles").startup == octax_core.get_spec("Cycles2").startup


@pytest.mark.parametrize("game_id", ["Duel", "Cycles1"])
def test_solo_env_is_player_1_against_an_idle_player_2(game_id):
    env, params = octax_core.make(game_id)
    assert env.num_actions == _env(game_id)[0].num_actions
    _, state = env.reset(jax.random.key(0), params)
    step = jax.jit(env.step_env)
    total = 0.0
    for t in range(300):
        _, state, reward, *_ = step(jax.random.key(t), state, jnp.int32(t % env.num_actions), params)
        total += float(reward)
    assert total == int(state.machine.V[5])  # player 1's points


# --- each seat's keys move its own side ---------------------------------------------------------


# Each seat's keys, tried from one start: env j of one rollout holds VARIANTS[game][j] (one
# action per seat) after WARMUP[game] no-op steps, for KEY_STEPS steps.
VARIANTS = {"Duel": [(0, 0), (1, 0), (0, 2)],
            "Cycles1": [(0, 0), (1, 0), (0, 1), (2, 0), (0, 2), (3, 4)]}
WARMUP = {"Duel": 6, "Cycles1": 20}
KEY_STEPS = {"Duel": 4, "Cycles1": 3}


@functools.cache
def _variants(game_id: str):
    warmup, steps = WARMUP[game_id], KEY_STEPS[game_id]
    plan = np.zeros((STEPS[game_id], NUM_ENVS, 2), np.int32)
    plan[warmup:warmup + steps, :len(VARIANTS[game_id])] = VARIANTS[game_id]
    V = _rollout(game_id, STEPS[game_id])(jax.random.key(3), plan)[2]
    return V[warmup + steps - 1].astype(int)


def _after(game_id: str, actions, warmup: int, steps: int):
    """The registers after `warmup` no-op steps, then `steps` steps of `actions` (one per seat)."""
    assert (warmup, steps) == (WARMUP[game_id], KEY_STEPS[game_id])
    return _variants(game_id)[VARIANTS[game_id].index(tuple(actions))]


def test_duel_keys_move_their_own_paddle_only():
    # the serve's pause: the ball waits at the centre while the paddles move (20 frames)
    base = _after("Duel", (0, 0), 6, 4)
    p1_up, p2_down = _after("Duel", (1, 0), 6, 4), _after("Duel", (0, 2), 6, 4)
    assert p1_up[duel.PAD1] < base[duel.PAD1] and p1_up[duel.PAD2] == base[duel.PAD2]
    assert p2_down[duel.PAD2] > base[duel.PAD2] and p2_down[duel.PAD1] == base[duel.PAD1]


@pytest.mark.parametrize("action, heading", [(1, cycles.UP), (2, cycles.DOWN)])
def test_cycles_keys_steer_their_own_cycle_only(action, heading):
    base = _after("Cycles1", (0, 0), 20, 3)
    assert (base[cycles.DIR1], base[cycles.DIR2]) == (cycles.RIGHT, cycles.LEFT)
    first = _after("Cycles1", (action, 0), 20, 3)
    second = _after("Cycles1", (0, action), 20, 3)
    assert (first[cycles.DIR1], first[cycles.DIR2]) == (heading, cycles.LEFT)
    assert (second[cycles.DIR1], second[cycles.DIR2]) == (cycles.RIGHT, heading)


def test_cycles_ignores_the_way_back():
    back = _after("Cycles1", (3, 4), 20, 3)  # player 1 left, player 2 right: both reversals
    assert (back[cycles.DIR1], back[cycles.DIR2]) == (cycles.RIGHT, cycles.LEFT)


# --- rewards --------------------------------------------------------------------------------------


@pytest.mark.parametrize("game_id", GAME_PARAMS)
@pytest.mark.parametrize("modes", [(SCRIPTED, RANDOM), (RANDOM, SCRIPTED)])
def test_rewards_are_each_seats_own_points_and_zero_sum(game_id, modes):
    rewards, done, V = _play(game_id, modes)
    points = V[..., 5].astype(int) - V[..., 6].astype(int)  # player 1's lead
    lead = np.concatenate([np.zeros((1, NUM_ENVS), int), points])
    np.testing.assert_array_equal(rewards[..., 0], np.diff(lead, axis=0))
    np.testing.assert_array_equal(rewards.sum(-1), 0)
    assert set(np.unique(rewards)) <= {-1.0, 0.0, 1.0}
    assert (rewards != 0).any()


# --- the scripted policy beats random; episodes end -----------------------------------------------


@pytest.mark.parametrize("game_id", GAME_PARAMS)
def test_scripted_policy_beats_random_from_either_seat(game_id):
    for seat, modes in ((0, (SCRIPTED, RANDOM)), (1, (RANDOM, SCRIPTED))):
        rewards, done, V = _play(game_id, modes)
        returns = rewards.sum(0)[:, seat]
        assert (returns > 0).mean() >= 0.9 and returns.mean() >= 4, (game_id, seat, returns)
        assert (returns[done[-1]] == (duel.WIN if game_id == "Duel" else cycles.WIN)).mean() >= 0.9


@pytest.mark.parametrize("game_id", GAME_PARAMS)
def test_random_play_is_even_and_episodes_end(game_id):
    rewards, done, V = _play(game_id, (RANDOM, RANDOM))
    assert done[-1].mean() >= 0.8, f"{game_id}: {done[-1].mean():.2f} of the random episodes ended"
    returns = rewards.sum(0)
    assert abs(returns[:, 0].mean()) < 2.5  # zero-sum, symmetric: even on average
    ended = V[-1, done[-1]]
    assert (np.maximum(ended[:, 5], ended[:, 6]) == (duel.WIN if game_id == "Duel" else cycles.WIN)).all()
    assert (ended[:, 14] == 1).all()


# --- Cycles' halves mirror each other ---------------------------------------------------------------

_MIRROR = np.array([0, 1, 2, 4, 3])  # actions: no-op, up, down, left <-> right


def test_cycles_mirrored_actions_give_the_mirrored_game():
    """Player 1's actions as player 2's, left and right swapped, and the other way round: the same
    match, mirrored: every round has the other winner, and where the cycles crashed mirrors too.
    (Within a move the ROM updates player 1 a few instructions before player 2, so a step may end
    between the two: the comparison is per round, not per step.)"""
    env, _ = _env("Cycles3")
    actions = np.random.default_rng(0).integers(0, env.num_actions, (300, NUM_ENVS, 2))
    plan = np.zeros((STEPS["Cycles3"], NUM_ENVS, 2), np.int32)
    run = _rollout("Cycles3", STEPS["Cycles3"])  # both from the same starts, with the same step keys
    rewards, _, V = (x[:300] for x in run(5, np.concatenate([actions, plan[300:]])))
    other, _, W = (x[:300] for x in run(5, np.concatenate([_MIRROR[actions[..., ::-1]], plan[300:]])))
    heading = np.array([cycles.UP, cycles.RIGHT, cycles.LEFT, cycles.DOWN])  # left <-> right
    V, W = V.astype(int), W.astype(int)
    events, other_events = [[] for _ in range(NUM_ENVS)], [[] for _ in range(NUM_ENVS)]
    for t in range(300):
        for i in np.flatnonzero(rewards[t, :, 0]):
            events[i].append((float(rewards[t, i, 0]), V[t, i, cycles.X1], V[t, i, cycles.X2], V[t, i, cycles.Y1],
                              V[t, i, cycles.Y2], V[t, i, cycles.DIR1], V[t, i, cycles.DIR2]))
        for i in np.flatnonzero(other[t, :, 0]):
            other_events[i].append((-float(other[t, i, 0]), 31 - W[t, i, cycles.X2], 31 - W[t, i, cycles.X1],
                                    W[t, i, cycles.Y2], W[t, i, cycles.Y1], heading[W[t, i, cycles.DIR2]],
                                    heading[W[t, i, cycles.DIR1]]))
    for i in range(NUM_ENVS):  # a round ending on the last step may be scored a step apart
        shared = min(len(events[i]), len(other_events[i]))
        assert abs(len(events[i]) - len(other_events[i])) <= 1 and events[i][:shared] == other_events[i][:shared], i
    assert sum(map(len, events)) > NUM_ENVS  # rounds were won and lost (not only drawn)
