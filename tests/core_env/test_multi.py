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


STEPS, ENVS = 40, 4  # the rollout's length, and the batch whose envs are also run alone


@pytest.fixture(scope="module")
def autoresetting(counters):
    """The autoresetting TwoCounters env and one jitted rollout of it, whose params are an argument:
    (env, params with the given sticky probability, rollout). `rollout(keys, actions, params)`
    resets one env per key of keys[0], then steps each with its own keys[t + 1] and actions[t];
    per step it returns (obs, state, reward, terminated, truncated, info), batched. Its actions
    come from the host, so the tests below run the one program per batch size."""
    env, _ = octax_core.make_multi(TWO_COUNTERS, rom=counters[3], autoreset=True)

    def rollout(keys, actions, params):
        _, state = jax.vmap(env.reset, in_axes=(0, None))(keys[0], params)

        def one(state, xs):
            step_keys, actions = xs
            obs, state, reward, terminated, truncated, info = jax.vmap(env.step, in_axes=(0, 0, 0, None))(
                step_keys, state, actions, params)
            return state, (obs, state, reward, terminated, truncated, info)

        return jax.lax.scan(one, state, (keys[1:], actions))[1]

    def params(repeat_action_probability):
        made, params = octax_core.make_multi(TWO_COUNTERS, rom=counters[3], autoreset=True,
                                             repeat_action_probability=repeat_action_probability)
        assert made.config == env.config  # the sticky probability is a param: the same program
        return params

    return env, params, jax.jit(rollout)


def test_same_seed_same_trajectory_whatever_the_batch(autoresetting):
    """Env i of a batch of 4 plays what env i alone plays, bit for bit: random actions per seat,
    sticky actions drawn from the step keys, episodes ended and autoreset within the rollout."""
    env, params, rollout = autoresetting
    params = params(0.25)
    keys = jax.random.split(jax.random.key(7), (STEPS + 1, ENVS))
    actions = np.random.default_rng(7).integers(0, env.num_actions, (STEPS, ENVS, 2)).astype(np.int32)
    batch = rollout(keys, actions, params)
    for i in (0, 2):
        alone = rollout(keys[:, i:i + 1], actions[:, i:i + 1], params)
        for together, by_itself in zip(jax.tree.leaves(batch), jax.tree.leaves(alone)):
            if jnp.issubdtype(together.dtype, jax.dtypes.prng_key):
                together, by_itself = jax.random.key_data(together), jax.random.key_data(by_itself)
            np.testing.assert_array_equal(np.asarray(together)[:, i], np.asarray(by_itself)[:, 0])
    assert np.asarray(batch[3]).any()  # episodes ended and were reset within the rollout
    assert not np.array_equal(batch[2][:, 0], batch[2][:, 1])  # the envs play differently


def test_autoreset_starts_a_new_episode_for_both_seats(autoresetting):
    """Seat 0 holds its second key (8 a step): the third step ends the episode at 24, and that
    step returns the new episode's state with the ended one's score and observation in info.
    One env of the rollout above (the same program: its batch of one)."""
    env, params, rollout = autoresetting
    keys = jax.random.split(jax.random.key(0), (STEPS + 1, 1))
    actions = np.broadcast_to(np.array([2, 0], np.int32), (STEPS, 1, 2))
    obs, state, reward, terminated, truncated, info = jax.tree.map(lambda x: x[:, 0], rollout(keys, actions, params(0.0)))
    assert np.asarray(terminated)[:3].tolist() == [False, False, True]
    assert bool(info["_final"][2]) and not np.asarray(info["_final"])[:2].any()
    assert info["final_observation"][2].shape == (2, 5, 32, 64)
    assert int(state.machine.V[2, 0]) == 0 and int(state.episode_step[2]) == 0
    np.testing.assert_array_equal(info["score"][2], [24.0, 0.0])
    np.testing.assert_array_equal(info["score"][3], [8.0, 0.0])  # the new episode plays on


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
