"""The one table of players (octax_core/env/players.py): each name is the player it says, as a
traced function of one game with the one signature."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.env.games import get_spec
from octax_core.env.players import check_player, make_player, noop, uniform

from two_player_games import TAKE_TURNS, TWO_COUNTERS

DRAWS = 4000


@pytest.fixture(scope="module")
def cycles_states(cycles):
    """32 Cycles games after 24 random steps each: states where the scripted player turns (before
    step 12 it goes straight in every game). Stepped one game at a time by the folder's compiled
    Cycles step (tests/core_env/conftest.py), then stacked: (32, ...) observations and states."""
    env, params, reset, step = cycles[False]
    keys = list(jax.random.split(jax.random.key(3), 32))
    games = [reset(key, params) for key in keys]
    for t in range(24):
        actions = np.asarray(jax.random.randint(jax.random.fold_in(jax.random.key(4), t), (32, 2), 0, env.num_actions))
        games = [step(key, state, action, params)[:2] for key, (_, state), action in zip(keys, games, actions)]
    obs, state = jax.tree.map(lambda *rows: np.stack(rows), *games)
    return env, obs, state


def _act_all(player, env, obs, state, seat, key=0):
    legal = jax.vmap(env.legal_action_mask)(state)[:, seat]
    keys = jax.random.split(jax.random.key(key), len(legal))
    act = jax.jit(jax.vmap(player, in_axes=(None, 0, 0, 0, None, 0)))
    return np.asarray(act(None, keys, obs[:, seat], state, jnp.int32(seat), legal))


@pytest.mark.parametrize("seat", [0, 1])
def test_eps0_and_scripted_are_the_games_scripted_policy(cycles_states, seat):
    env, obs, state = cycles_states
    policy = env.seats.scripted_policy
    expected = np.asarray(jax.vmap(lambda machine: policy(machine, seat))(state.machine))
    assert len(set(expected.tolist())) > 1  # the states make the bot choose
    for name in ("scripted", "eps0"):
        np.testing.assert_array_equal(_act_all(make_player(name, env.spec), env, obs, state, seat), expected)


def test_eps1_is_uniform_over_the_legal_actions(two_counters_rom):
    env, params = octax_core.make_multi(TWO_COUNTERS, rom=two_counters_rom)
    obs, state = env.reset(jax.random.key(0), params)
    legal = jnp.array([True, False, True])  # action 1 closed
    keys = jax.random.split(jax.random.key(1), DRAWS)
    # eps1 draws its random action with the second half of its key: `same` is `uniform` given those
    players = {name: make_player(name, TWO_COUNTERS) for name in ("eps1", "eps0.5", "random")}
    players["same"] = lambda params, key, *rest: uniform(params, jax.random.split(key)[1], *rest)

    @jax.jit  # every player's draws in one program
    def play(keys, obs, state, legal):
        return {name: jax.vmap(p, in_axes=(None, 0, None, None, None, None))(None, keys, obs, state, jnp.int32(0), legal)
                for name, p in players.items()}

    drawn = {name: np.asarray(actions) for name, actions in play(keys, obs[0], state, legal).items()}
    eps1 = drawn["eps1"]
    counts = np.bincount(eps1, minlength=3) / DRAWS
    assert counts[1] == 0 and abs(counts[0] - 0.5) < 0.04 and abs(counts[2] - 0.5) < 0.04
    np.testing.assert_array_equal(eps1, drawn["same"])
    # eps0.5: the scripted action (2) half the time, else uniform over {0, 2}: 2 three times in four
    half = drawn["eps0.5"]
    assert abs((half == 2).mean() - 0.75) < 0.04 and not (half == 1).any()
    assert (drawn["random"] != 1).all()


def test_random_waits_on_the_other_seats_turn(take_turns_rom):
    env, params = octax_core.make_multi(TAKE_TURNS, rom=take_turns_rom)
    obs, state = env.reset(jax.random.key(0), params)
    legal = env.legal_action_mask(state)  # seat 0 moves: seat 1 may only wait
    keys = jax.random.split(jax.random.key(2), 200)
    for seat, allowed in ((0, {0, 1}), (1, {0})):
        actions = jax.vmap(uniform, in_axes=(None, 0, None, None, None, None))(
            None, keys, obs[seat], state, jnp.int32(seat), legal[seat])
        assert set(np.asarray(actions).tolist()) == allowed
    assert int(noop(None, keys[0], obs[0], state, jnp.int32(0), legal[0])) == 0


def test_names_are_checked_with_the_valid_choices():
    cycles, racer = get_spec("Cycles"), get_spec("SpaceRacer")
    assert check_player("eps0.50", cycles) == "eps0.5"
    assert check_player("random", racer) == "random"
    with pytest.raises(ValueError, match=r"unknown player 'greedy'; valid: 'random', 'noop', 'scripted'.*eps<p>"):
        check_player("greedy", cycles)
    with pytest.raises(ValueError, match=r"SpaceRacer has no scripted player.*'random', 'noop'"):
        make_player("eps0.25", racer)
    with pytest.raises(ValueError, match=r"eps of 'eps1.5' must be a number in \[0, 1\]"):
        make_player("eps1.5", cycles)
