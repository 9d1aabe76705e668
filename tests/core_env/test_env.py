"""The functional env API on the Counter test game (tests/counter_game.py), so every number below
is worked by hand: holding key 1 for a 4-frame step scores 4, the game is over when V0 >= 24.
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.env.testing import check_env

from counter_game import COUNTER, COUNTER_ROM, GOAL
from two_player_games import TWO_COUNTERS, TWO_COUNTERS_ROM


@pytest.fixture(scope="module")
def rom_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("roms") / "counter.ch8"
    path.write_bytes(COUNTER_ROM)
    return path


@pytest.fixture(scope="module")
def counter(rom_path):
    """make() plus jitted single-env reset/step, built (and traced) once per set of overrides for the module."""
    built = {}

    def build(**overrides):
        env, params = octax_core.make(COUNTER, rom=rom_path, **overrides)
        # options that are EnvParams (arguments of the compiled step) share the program of the env
        # without them: the same config, so the same traced step
        key = tuple(sorted((k, v) for k, v in overrides.items() if k not in PARAM_OPTIONS))
        if key not in built:
            built[key] = env, jax.jit(env.reset), jax.jit(env.step)
        assert built[key][0].config == env.config
        return built[key][0], params, *built[key][1:]
    return build


PARAM_OPTIONS = {"max_episode_steps", "repeat_action_probability"}


@functools.lru_cache(maxsize=None)
def batched_reset(env):
    """`env.reset` over a batch of keys, jitted once per env (the `counter` builder's: one per config)."""
    return jax.jit(jax.vmap(env.reset, in_axes=(0, None)))


def noop_keys():
    """The batch of keys the no-op start tests reset (one batch size: one compiled reset per env)."""
    return jax.random.split(jax.random.key(3), 16)

# The one config besides the default that the tests step: the same-step autoreset's, which the
# obs_scale=255 observation test shares (autoreset leaves a step that ends no episode as it is,
# and the scale changes a lit pixel's value, not which pixels are lit).
AUTORESET_255 = dict(autoreset=True, obs_scale=255)


def _play(step, state, params, actions):
    rows = []
    for t, action in enumerate(actions):
        obs, state, reward, terminated, truncated, info = step(jax.random.key(t), state, action, params)
        rows.append((float(reward), bool(terminated), bool(truncated), int(info["episode_step"]), float(info["score"])))
    return rows, state, obs, info


def test_contract_suite_passes(rom_path):
    check_env(COUNTER, rom=rom_path, obs_scale=255, autoreset=True, frames_per_step=2)


def test_the_contract_suite_has_its_public_address():
    import octax_core.testing

    assert octax_core.testing.check_env is check_env is octax_core.check_env


def test_contract_suite_catches_a_broken_game(rom_path):
    import dataclasses
    broken = dataclasses.replace(COUNTER, score_fn=lambda s: s.V[0] / 0.0)  # inf / nan rewards
    # one env: the batch of one is also the env run alone, so the suite compiles one step, not two
    with pytest.raises(AssertionError, match="non-finite rewards"):
        check_env(broken, rom=rom_path, num_envs=1)


def test_reward_and_termination_table(counter):
    env, params, reset, step = counter()
    assert env.num_actions == 3 and env.observation_shape == (4, 32, 64)
    obs, state = reset(jax.random.key(0), params)
    rows, state, obs, info = _play(step, state, params, [1, 1, 2, 0, 1, 1, 1])
    # (reward, terminated, truncated, episode_step, score): key 1 = +4 a step, key 2 = +8.
    assert rows == [
        (4.0, False, False, 1, 4.0),
        (4.0, False, False, 2, 8.0),
        (8.0, False, False, 3, 16.0),
        (0.0, False, False, 4, 16.0),
        (4.0, False, False, 5, 20.0),
        (4.0, True, False, 6, 24.0),
        (0.0, True, False, 6, 24.0),  # an ended episode stands still
    ]
    assert int(info["lives"]) == 0


def test_ended_episode_keeps_state_and_observation(counter):
    env, params, reset, step = counter()
    _, state = reset(jax.random.key(0), params)
    _, state, obs, _ = _play(step, state, params, [2, 2, 2])
    assert bool(state.done)
    obs_after, state_after, reward, terminated, _, _ = step(jax.random.key(9), state, 1, params)
    assert float(reward) == 0.0 and bool(terminated)
    for a, b in zip(jax.tree.leaves(state), jax.tree.leaves(state_after)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    np.testing.assert_array_equal(np.asarray(obs_after)[0], np.asarray(obs)[-1])


def test_truncation(counter):
    env, params, reset, step = counter(max_episode_steps=3)
    _, state = reset(jax.random.key(0), params)
    rows, *_ = _play(step, state, params, [0, 0, 0, 0])
    assert [(r[1], r[2]) for r in rows] == [(False, False), (False, False), (False, True), (False, True)]


def test_same_step_autoreset(counter):
    env, params, reset, step = counter(**AUTORESET_255)
    _, state = reset(jax.random.key(0), params)
    rows, state, obs, info = _play(step, state, params, [2, 2, 2])
    assert rows[-1][:2] == (8.0, True)
    # The returned state and observation start the next episode; the ended one is in info.
    assert int(state.episode_step) == 0 and float(state.score) == 0.0 and not bool(state.done)
    assert bool(info["_final"]) and float(info["final_info"]["score"]) == 24.0
    final = np.asarray(info["final_observation"])
    lit_rows = np.flatnonzero(final[-1].any(axis=1))
    assert list(lit_rows) == list(range(GOAL, GOAL + 5))  # the digit drawn at y = V0 = 24
    assert not np.asarray(obs).any()  # the reset screen is blank (nothing has run yet)
    rows, *_ = _play(step, state, params, [1])
    assert rows == [(4.0, False, False, 1, 4.0)]


def test_batched_autoreset_is_the_select_it_gates(counter):
    """`Env.autoreset` runs under `gate.when_any`: over a batch it must equal the plain select
    (a new episode where the mask holds) whether no env, some or all ended, bit for bit."""
    # The episodes to restart are the no-op starts of the test below (the same env and batch, so
    # the same compiled reset); restarted with other keys they draw other starts.
    env, params, _, _ = counter(noop_max=30)
    obs, state = batched_reset(env)(noop_keys(), params)
    def plain(key, mask, obs, state):
        fresh = env.reset_env(key, params)
        return jax.tree.map(lambda new, old: jax.numpy.where(mask, new, old), fresh, (obs, state))

    @jax.jit  # both in one program
    def gated_and_plain(keys, mask, obs, state):
        return (jax.vmap(env.autoreset, in_axes=(0, 0, 0, 0, None))(keys, mask, obs, state, params),
                jax.vmap(plain)(keys, mask, obs, state))

    new_keys = jax.random.split(jax.random.key(9), 16)
    for mask in (np.zeros(16, bool), np.arange(16) % 3 == 1, np.ones(16, bool)):
        got, want = gated_and_plain(new_keys, mask, obs, state)
        for a, b in zip(jax.tree.leaves(got), jax.tree.leaves(want)):
            if jax.numpy.issubdtype(a.dtype, jax.dtypes.prng_key):
                a, b = jax.random.key_data(a), jax.random.key_data(b)
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    assert not np.array_equal(np.asarray(want[0]), np.asarray(obs))  # the restarted episodes start elsewhere


def test_observation_holds_each_frame_and_its_scale(counter):
    for scale, options in ((1, {}), (255, AUTORESET_255)):
        env, params, reset, step = counter(**options)
        _, state = reset(jax.random.key(0), params)
        obs, *_ = step(jax.random.key(1), state, 1, params)
        obs = np.asarray(obs)
        assert obs.dtype == np.uint8 and set(np.unique(obs)) == {0, scale}
        # Frame f shows the digit at y = f + 1 (key 1 adds 1 per frame).
        tops = [int(np.flatnonzero(frame.any(axis=1))[0]) for frame in obs]
        assert tops == [1, 2, 3, 4]


def test_sticky_actions(counter):
    env, params, reset, step = counter(repeat_action_probability=1.0)
    _, state = reset(jax.random.key(0), params)
    rows, *_ = _play(step, state, params, [1, 2, 1])
    assert [r[0] for r in rows] == [0.0, 0.0, 0.0]  # the first action (no-op) repeats forever
    env, params, reset, step = counter(repeat_action_probability=0.0)
    _, state = reset(jax.random.key(0), params)
    rows, *_ = _play(step, state, params, [1, 2, 1])
    assert [r[0] for r in rows] == [4.0, 8.0, 4.0]


def test_noop_reset_runs_a_random_number_of_noop_steps(counter):
    for noop_max, expect_blank in ((0, True), (30, False)):
        env, params, _, _ = counter(noop_max=noop_max)
        obs, state = batched_reset(env)(noop_keys(), params)
        lit = np.asarray(obs).reshape(16, -1).any(axis=1)
        assert not lit.any() if expect_blank else lit.sum() >= 12  # P(0 no-ops) = 1/31 per env
        assert np.all(np.asarray(state.episode_step) == 0) and np.all(np.asarray(state.score) == 0)


def test_random_state_follows_the_reset_key(counter):
    env, params, reset, step = counter()
    positions = set()
    for seed in range(6):
        _, state = reset(jax.random.key(seed), params)
        obs, *_ = step(jax.random.key(0), state, 0, params)
        positions.add(int(np.flatnonzero(np.asarray(obs)[0].any(axis=0))[0]))
    assert len(positions) > 1  # the digit's x comes from CXNN, seeded by the reset key


def test_bad_actions_are_refused(counter):
    env, params, reset, step = counter()
    _, state = reset(jax.random.key(0), params)
    with pytest.raises(ValueError, match=r"valid actions are 0\.\.2"):
        env.step(jax.random.key(0), state, 3, params)
    with pytest.raises(TypeError, match="one integer"):
        env.step(jax.random.key(0), state, 1.0, params)


@pytest.fixture(scope="module")
def env_kinds(rom_path):
    """One env of each kind, each with its seats' action shape: one player, two seats, a mix."""
    two = rom_path.parent / "two_counters.ch8"
    two.write_bytes(TWO_COUNTERS_ROM)
    kinds = {"one player": octax_core.make(COUNTER, rom=rom_path),
             "two seats": octax_core.make_multi(TWO_COUNTERS, rom=two),
             "mix": octax_core.make_mix([COUNTER, COUNTER], roms=[rom_path, rom_path])}
    return {kind: (env, params, env.reset(jax.random.key(0), params)[1]) for kind, (env, params) in kinds.items()}


def _seated(env, value):
    """`value` as the env's step takes it: alone, or in the second seat's place (seat 0 plays 1)."""
    return value if not env._action_shape else np.array([1, value], np.asarray(value).dtype)


@pytest.mark.parametrize("kind, name", [("one player", "Counter"), ("two seats", "TwoCounters"),
                                        ("mix", r"mix\(Counter, Counter\)")])
@pytest.mark.parametrize("value", [np.int64(2**32 + 1), np.int64(-2**32 + 1), 2**32 + 1, np.uint64(2**63), 3, -1])
def test_every_kind_refuses_an_out_of_range_action_by_its_value(env_kinds, kind, name, value):
    """One check for all three kinds: the value as given is compared, never a narrowed one."""
    env, params, state = env_kinds[kind]
    seat = " of seat second_0" if kind == "two seats" else ""
    message = rf"^{name}: action {int(value)}{seat} is out of range; valid actions are 0\.\.2 \(0 = no-op\)$"
    with pytest.raises(ValueError, match=message):
        env.step(jax.random.key(0), state, _seated(env, value), params)
    form = r"actions are 2 integers, one per seat \(first_0, second_0\), each" if kind == "two seats" else \
        "an action is one integer"
    with pytest.raises(TypeError, match=rf"^{name}: {form} in 0\.\.2; got float32"):
        env.step(jax.random.key(0), state, _seated(env, np.float32(1)), params)
    with pytest.raises(TypeError, match=r"got int64 of shape \(3,\)"):
        env.step(jax.random.key(0), state, np.zeros(3, np.int64), params)
    np.testing.assert_array_equal(env._check_action(_seated(env, np.int64(2))), _seated(env, 2))


@pytest.mark.parametrize("kind", ["one player", "two seats", "mix"])
def test_a_traced_wide_action_is_range_checked_before_it_is_narrowed(env_kinds, kind):
    """Under jax_enable_x64 an int64 2**32 + 1 is out of range, so no-op (0); narrowed to int32
    first it would have wrapped to 1, a valid key."""
    env, _, _ = env_kinds[kind]
    with jax.enable_x64(True):
        check = jax.jit(env._check_action)
        for value, expected in ((2**32 + 1, 0), (-2**32 + 1, 0), (2, 2), (3, 0)):
            action = check(jnp.asarray(_seated(env, value), jnp.int64))
            assert action.dtype == jnp.int32
            np.testing.assert_array_equal(action, _seated(env, expected))
    with pytest.raises(TypeError, match="got float32"):
        jax.jit(env._check_action)(jnp.asarray(_seated(env, 1.0), jnp.float32))


def test_the_check_is_the_base_env_s_alone():
    """MultiEnv and MixEnv differ in action shape and name, not in how an action is checked."""
    from octax_core.env.mix import MixEnv
    from octax_core.env.multi import MultiEnv

    assert [kind.__name__ for kind in (MultiEnv, MixEnv) if "_check_action" in vars(kind)] == []


@pytest.mark.parametrize("overrides, error, message", [
    ({"frame_skip": 4}, TypeError, "valid: .*frames_per_step"),
    ({"obs_scale": 2}, ValueError, "obs_scale must be one of 1, 255"),
    ({"frames_per_step": 0}, ValueError, "frames_per_step must be an int >= 1"),
    ({"repeat_action_probability": 1.5}, ValueError, r"must be a number in \[0, 1\]"),
    ({"noop_max": -1}, ValueError, "noop_max must be an int >= 0"),
    ({"max_episode_steps": 0}, ValueError, "max_episode_steps must be an int >= 1"),
    ({"autoreset": "yes"}, ValueError, "autoreset must be True or False"),
])
def test_bad_overrides(rom_path, overrides, error, message):
    with pytest.raises(error, match=message):
        octax_core.make(COUNTER, rom=rom_path, **overrides)


def test_unknown_game_says_where_the_valid_ids_are():
    with pytest.raises(KeyError, match=r"unknown game 'NoSuchGame' \(see octax_core.list_games\(\)"):
        octax_core.make("NoSuchGame")


def test_a_rom_with_another_hash_is_refused(tmp_path):
    wrong = tmp_path / "counter.ch8"
    wrong.write_bytes(COUNTER_ROM + b"\x00")
    with pytest.raises(ValueError, match=COUNTER.rom_sha1):
        octax_core.make(COUNTER, rom=wrong)
