"""The two-player functional env (`octax_core.make_multi`) on two games worked by hand
(tests/two_player_games.py) and on the archive's Space Racer."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.env.multi import MultiEnv

from counter_game import COUNTER
from two_player_games import GOAL, TAKE_TURNS, TURNS_GOAL, TWO_COUNTERS


@pytest.fixture(scope="module")
def counters(two_counters_rom):
    env, params = octax_core.make_multi(TWO_COUNTERS, rom=two_counters_rom)
    return env, params, jax.jit(env.step), two_counters_rom


@pytest.fixture(scope="module")
def turns(take_turns_rom):
    env, params = octax_core.make_multi(TAKE_TURNS, rom=take_turns_rom)
    return env, params, jax.jit(env.step)


def _play(step, env, params, actions_seq, key=0):
    obs, state = env.reset(jax.random.key(key), params)
    out = []
    for t, actions in enumerate(actions_seq):
        obs, state, reward, terminated, truncated, info = step(jax.random.key(100 + t), state, jnp.array(actions), params)
        out.append((obs, state, reward, terminated, truncated, info))
    return out


def test_observations_are_per_seat_with_a_player_plane(counters):
    env, params, step, _ = counters
    obs, state = env.reset(jax.random.key(0), params)
    assert env.num_actions == 3 and env.players == 2 and env.agents == ("first_0", "second_0")
    assert obs.shape == (2, 5, 32, 64) == (2, *env.observation_shape) and obs.dtype == jnp.uint8
    np.testing.assert_array_equal(obs[0, :4], obs[1, :4])  # one screen, two readers
    assert (obs[0, 4] == 0).all() and (obs[1, 4] == 1).all()  # the player plane
    obs, *_ = step(jax.random.key(1), state, jnp.array([1, 0]), params)
    assert obs.shape == (2, 5, 32, 64) and (obs[1, 4] == 1).all() and (obs[0, 4] == 0).all()
    env255, params255 = octax_core.make_multi(TWO_COUNTERS, rom=counters[3], obs_scale=255)
    obs, _ = env255.reset(jax.random.key(0), params255)
    assert (obs[1, 4] == 255).all() and set(np.unique(obs[:, :4]).tolist()) <= {0, 255}


@pytest.mark.parametrize("actions, scores", [
    ((0, 0), (0, 0)), ((1, 0), (4, 0)), ((2, 0), (8, 0)), ((0, 1), (0, 4)), ((0, 2), (0, 8)), ((1, 2), (4, 8)),
])
def test_each_seats_keys_reach_the_one_keypad(counters, actions, scores):
    env, params, step, _ = counters
    (_, state, reward, terminated, truncated, info), = _play(step, env, params, [actions])
    np.testing.assert_array_equal(reward, np.array(scores, np.float32))
    np.testing.assert_array_equal(info["score"], np.array(scores, np.float32))
    assert reward.shape == (2,) and reward.dtype == jnp.float32 and terminated.shape == () and not terminated
    assert int(state.machine.V[0]) == scores[0] and int(state.machine.V[1]) == scores[1]
    assert int(info["current_player"]) == -1 and bool(info["legal_action_mask"].all())


def test_the_episode_is_shared_and_ends_for_both(counters):
    env, params, step, _ = counters
    steps = _play(step, env, params, [(0, 2)] * 4)
    assert [bool(s[3]) for s in steps] == [False, False, True, True]  # V1: 8, 16, 24 -> over
    assert float(steps[-1][2].sum()) == 0.0  # an ended episode stands still
    assert int(steps[2][1].machine.V[1]) == GOAL


def test_actions_are_checked_outside_jit(counters):
    env, params, _, _ = counters
    _, state = env.reset(jax.random.key(0), params)
    with pytest.raises(TypeError, match=r"2 integers, one per seat \(first_0, second_0\)"):
        env.step(jax.random.key(0), state, jnp.array([1, 0, 0]), params)
    with pytest.raises(TypeError, match="one per seat"):
        env.step(jax.random.key(0), state, 1, params)
    with pytest.raises(TypeError, match="one per seat"):
        env.step(jax.random.key(0), state, jnp.array([1.0, 0.0]), params)
    with pytest.raises(ValueError, match=r"action 3 of seat first_0 is out of range; valid actions are 0\.\.2"):
        env.step(jax.random.key(0), state, jnp.array([3, 0]), params)
    with pytest.raises(ValueError, match="out of range"):
        env.step(jax.random.key(0), state, jnp.array([0, -1]), params)


def test_a_one_player_game_is_refused_with_the_two_player_list():
    with pytest.raises(ValueError, match="one-player game; two-player games: .*SpaceRacer"):
        octax_core.make_multi(COUNTER)
    with pytest.raises(KeyError, match="unknown game 'Nope'"):
        octax_core.make_multi("Nope")
    with pytest.raises(TypeError, match="unknown keyword"):
        octax_core.make_multi("SpaceRacer", players=3)


def test_turns_alternate_and_the_waiting_seat_may_only_wait(turns):
    env, params, step = turns
    obs, state = env.reset(jax.random.key(0), params)
    info = env.info(state)
    assert int(info["current_player"]) == 0 and env.turn_based
    np.testing.assert_array_equal(info["legal_action_mask"], [[True, True], [True, False]])
    # seat 1 moving out of turn is played as no-op; seat 0's move passes the turn
    moves = [(0, 1), (1, 0), (1, 0), (0, 1), (1, 1)]
    steps = _play(step, env, params, moves)
    movers = [int(s[5]["current_player"]) for s in steps]
    assert movers == [0, 1, 1, 0, 1]
    counters = [(int(s[1].machine.V[0]), int(s[1].machine.V[1])) for s in steps]
    assert counters == [(0, 0), (1, 0), (1, 0), (1, 1), (2, 1)]
    rewards = np.stack([s[2] for s in steps])
    np.testing.assert_array_equal(rewards.sum(axis=1), 0)  # zero-sum
    np.testing.assert_array_equal(rewards[:, 0], [0, 1, 0, -1, 1])
    np.testing.assert_array_equal(steps[1][5]["legal_action_mask"], [[True, False], [True, True]])


def test_a_closed_action_is_noop_under_jit_too(turns):
    env, params, step = turns
    _, state = env.reset(jax.random.key(0), params)
    _, out_of_turn, *_ = step(jax.random.key(1), state, jnp.array([0, 1]), params)
    _, waited, *_ = step(jax.random.key(1), state, jnp.array([0, 0]), params)
    jax.tree.map(np.testing.assert_array_equal, out_of_turn, waited)


def test_a_game_that_is_not_solo_is_refused_by_make_and_left_out_of_list_games():
    assert not TAKE_TURNS.solo and TAKE_TURNS.players == 2
    with pytest.raises(ValueError, match="played by two.*make_multi"):
        octax_core.make(TAKE_TURNS)
    assert "SpaceRacer" in octax_core.list_games(players=2) and "SpaceRacer" in octax_core.list_games()
    assert all(octax_core.get_spec(g).seats is not None for g in octax_core.list_games(players=2))
    assert set(octax_core.list_games(players=1)) == set(octax_core.list_games())
    with pytest.raises(ValueError, match="players must be 1 or 2"):
        octax_core.list_games(players=3)


def _random_rollout(env, params, keys, steps):
    """One env per key under vmap, uniform random actions per seat drawn from its own key, autoreset."""
    obs, state = jax.vmap(env.reset, in_axes=(0, None))(keys, params)

    def one(carry, t):
        state, keys = carry
        split = jax.vmap(lambda k: jax.random.split(k, 3))(keys)
        actions = jax.vmap(lambda k: jax.random.randint(k, (2,), 0, env.num_actions))(split[:, 1])
        obs, state, reward, terminated, truncated, info = jax.vmap(env.step, in_axes=(0, 0, 0, None))(
            split[:, 2], state, actions, params)
        return (state, split[:, 0]), (obs, reward, terminated, truncated, info["score"])

    return jax.lax.scan(one, (state, keys), jnp.arange(steps))[1]


def test_same_seed_same_trajectory_whatever_the_batch(counters):
    _, _, _, path = counters
    env, params = octax_core.make_multi(TWO_COUNTERS, rom=path, autoreset=True, repeat_action_probability=0.25)
    rollout = jax.jit(_random_rollout, static_argnums=(0, 3))
    keys = jax.random.split(jax.random.key(7), 4)
    batch = rollout(env, params, keys, 40)
    for i in (0, 2):
        alone = rollout(env, params, keys[i:i + 1], 40)
        for together, by_itself in zip(batch, alone):
            np.testing.assert_array_equal(together[:, i], by_itself[:, 0])
    assert np.asarray(batch[2]).any()  # episodes ended and were reset within the rollout
    assert not np.array_equal(batch[1][:, 0], batch[1][:, 1])  # the envs play differently


def test_autoreset_starts_a_new_episode_for_both_seats(counters):
    _, _, _, path = counters
    env, params = octax_core.make_multi(TWO_COUNTERS, rom=path, autoreset=True)
    step = jax.jit(env.step)
    obs, state = env.reset(jax.random.key(0), params)
    for t in range(3):
        obs, state, reward, terminated, truncated, info = step(jax.random.key(t), state, jnp.array([2, 0]), params)
    assert bool(terminated) and bool(info["_final"])
    assert info["final_observation"].shape == (2, 5, 32, 64)
    assert int(state.machine.V[0]) == 0 and int(state.episode_step) == 0
    np.testing.assert_array_equal(info["score"], [24.0, 0.0])


def test_sticky_actions_are_per_seat(counters):
    _, _, step, path = counters  # the sticky probability is a param: the fixture's compiled step plays it
    env, params = octax_core.make_multi(TWO_COUNTERS, rom=path, repeat_action_probability=1.0)
    assert env.config == counters[0].config
    _, state = env.reset(jax.random.key(0), params)
    _, state, reward, *_ = step(jax.random.key(0), state, jnp.array([1, 2]), params)
    np.testing.assert_array_equal(reward, [0.0, 0.0])  # both repeat their first action, no-op
    assert state.last_action.shape == (2,)


# Space Racer's seats each move their own ship, one at a time and both at once:
# tests/core_games/test_two_player_archive.py (test_space_racer_seat_keys_move_their_own_ship).


def test_multi_env_is_the_one_player_env_extended():
    assert issubclass(MultiEnv, octax_core.Env)
    assert MultiEnv.step is octax_core.Env.step and MultiEnv.autoreset is octax_core.Env.autoreset
