"""make_multi(game, mirror=True): seat 1 sees the game's mirror image and plays through the game's
mirror permutation of actions (`Seats.mirror`, `Seats.mirror_actions`); scores untouched."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.env.config import mirrored_games
from octax_core.env.games import Seats, get_spec

CYCLES = get_spec("Cycles")
N, STEPS = 4, 160


# Every test here steps Cycles through the folder's `cycles` fixture (tests/core_env/conftest.py):
# one compiled step per mirror setting, one env at a time; the players' actions are small
# programs of their own, so the game played does not make another compile of the machine.


@pytest.fixture(scope="module")
def mirrored_play(cycles):
    """Cycles from N resets: seat 0 plays the scripted player, seat 1 the same action in its mirrored
    view (its own mirror image on the machine). Each step's observations, rewards and V3, (N, ...)."""
    env, params, reset, step = cycles[True]
    same_action = jax.jit(lambda machine: jnp.stack([CYCLES.seats.scripted_policy(machine, 0)] * 2))
    states = [reset(key, params)[1] for key in jax.random.split(jax.random.key(3), N)]
    steps = []
    for t in range(STEPS):
        rows = []
        for i, key in enumerate(jax.random.split(jax.random.key(100 + t), N)):
            obs, states[i], rewards, *_ = step(key, states[i], same_action(states[i].machine), params)
            rows.append((np.asarray(obs), np.asarray(rewards), np.asarray(states[i].machine.V)[3]))
        steps.append(tuple(np.stack(column) for column in zip(*rows)))
    return steps


def _wall_complete(frames):
    """Every frame shows the arena's wall: rows 0, 1, 30, 31 and columns 0, 1, 62, 63 lit (a round is on)."""
    rows = frames[:, [0, 1, 30, 31], :].all(axis=(1, 2))
    columns = frames[:, :, [0, 1, 62, 63]].all(axis=(1, 2))
    return bool((rows & columns).all())


def test_mirrored_cycles_see_the_same_game_but_for_a_sprite_drawn_a_frame_late(mirrored_play):
    # The ROM moves both cycles together but draws their new cells one frame apart (one sprite a
    # frame), so once a move one frame shows one new cell and not yet its mirror image: a 2x2 cell
    # and its image, 8 pixels; a new round's obstacles are drawn so too, in pairs (4x4 blocks).
    # Every other frame of a round is the same for both seats, bit for bit.
    in_play = cells = 0
    for obs, rewards, x1 in mirrored_play:
        assert (rewards == 0).all()  # mirrored play: every round is drawn
        for env_obs, x in zip(obs, x1):
            seat0, seat1 = env_obs[0, :-1], env_obs[1, :-1]
            if not (_wall_complete(seat0) and _wall_complete(seat1)):
                continue  # between rounds: the wall is cleared and drawn again sprite by sprite
            in_play += 1
            diff = seat0 != seat1
            frames = np.flatnonzero(diff.any(axis=(1, 2)))
            assert not (np.diff(frames) == 1).any()  # a sprite's image is drawn in the next frame
            for frame in frames:
                ys, xs = np.nonzero(diff[frame])
                left = xs < 32
                assert sorted(zip(ys[left], xs[left])) == sorted(zip(ys[~left], 63 - xs[~left]))  # a pair
                size = int(np.sqrt(left.sum()))  # the left one is a filled square: a cell or a block
                assert size in (2, 4) and left.sum() == size * size
                assert ys.max() - ys.min() == xs[left].max() - xs[left].min() == size - 1
                cells += size == 2
    assert in_play > 400 and 0.2 < cells / in_play < 0.8  # a move is two steps: about one in two


def test_mirror_flips_seat_1_and_maps_its_actions_and_nothing_else(cycles):
    # The same game played with mirror off, seat 1's actions mapped through the permutation by
    # hand: seat 0's observation, the rewards, the state are the same, bit for bit, and seat 1's
    # observation is seat 0's screens flipped left-right (its player plane as before).
    (plain, params, reset_plain, step_plain), (mirrored, _, reset_mirrored, step_mirrored) = cycles[False], cycles[True]
    permutation = np.asarray(CYCLES.seats.mirror_actions)
    obs_p, state_p = reset_plain(jax.random.key(7), params)
    obs_m, state_m = reset_mirrored(jax.random.key(7), params)
    rng = np.random.default_rng(0)
    for t in range(60):
        np.testing.assert_array_equal(obs_m[0], obs_p[0])
        np.testing.assert_array_equal(obs_m[1, :-1], np.flip(np.asarray(obs_p[1, :-1]), axis=-1))
        np.testing.assert_array_equal(obs_m[1, -1], obs_p[1, -1])
        np.testing.assert_array_equal(obs_p[1, :-1], obs_p[0, :-1])  # off: one screen, both seats
        actions = rng.integers(0, mirrored.num_actions, 2)
        key = jax.random.key(t)
        obs_p, state_p, rewards_p, *_ = step_plain(key, state_p, jnp.asarray([actions[0], permutation[actions[1]]]),
                                                   params)
        obs_m, state_m, rewards_m, *_ = step_mirrored(key, state_m, jnp.asarray(actions), params)
        np.testing.assert_array_equal(rewards_m, rewards_p)
        for leaf_m, leaf_p in zip(jax.tree.leaves(state_m), jax.tree.leaves(state_p)):
            np.testing.assert_array_equal(leaf_m, leaf_p)


def test_mirror_off_is_the_one_player_screen(cycles):
    # The default path is unchanged: each seat's screens are the one-player env's, bit for bit.
    multi, params, multi_reset, multi_step = cycles[False]
    solo, solo_params = octax_core.make("Cycles")
    # jitted: an env step run op by op is thousands of tiny programs, compiled or read one by one
    solo_step = jax.jit(solo.step)
    obs_m, state_m = multi_reset(jax.random.key(1), params)
    obs_s, state_s = jax.jit(solo.reset)(jax.random.key(1), solo_params)
    for t in range(20):
        np.testing.assert_array_equal(obs_m[:, :-1], np.stack([obs_s, obs_s]))
        action = t % solo.num_actions
        obs_m, state_m, *_ = multi_step(jax.random.key(t), state_m, jnp.asarray([action, 0]), params)
        obs_s, state_s, *_ = solo_step(jax.random.key(t), state_s, jnp.int32(action), solo_params)


def test_mirror_permutes_seat_1s_legal_mask_and_maps_back(cycles):
    env, params, reset, _ = cycles[True]
    _, state = reset(jax.random.key(0), params)
    assert env.mirrored and not cycles[False][0].mirrored
    assert env.legal_action_mask(state).all()  # simultaneous: every action open, mirrored or not
    actions = jnp.asarray([3, 3])
    np.testing.assert_array_equal(env.mirror_action(actions), [3, 4])
    np.testing.assert_array_equal(env.mirror_action(env.mirror_action(actions)), actions)
    np.testing.assert_array_equal(cycles[False][0].mirror_action(actions), actions)


def test_mirror_actions_are_involutions_that_keep_noop():
    for game in mirrored_games():
        permutation = get_spec(game).seats.mirror_actions
        assert permutation[0] == 0
        assert [permutation[a] for a in permutation] == list(range(len(permutation)))
    assert "Cycles" in mirrored_games() and "Paddles" not in mirrored_games()
    keys = ((1, 2, 3, 4), (5, 6, 7, 8))
    for bad in ((0, 2, 3, 4, 1), (1, 0, 2, 4, 3), (0, 1, 2, 3)):
        with pytest.raises(ValueError, match="mirror_actions must be a permutation"):
            Seats(action_keys=keys, score_fn=lambda s: s, mirror="left-right", mirror_actions=bad)
    with pytest.raises(ValueError, match="unknown mirror axis 'diagonal'; valid: left-right, top-bottom"):
        Seats(action_keys=keys, score_fn=lambda s: s, mirror="diagonal", mirror_actions=(0, 1, 2, 4, 3))
    with pytest.raises(ValueError, match="both or neither"):
        Seats(action_keys=keys, score_fn=lambda s: s, mirror="left-right")


def test_mirror_is_refused_where_there_is_no_mirrored_second_seat():
    listed = ", ".join(mirrored_games())
    for game in ("Paddles", "TankArchive"):  # measured not symmetric: docs/multiplayer.md, "Mirrored seats"
        with pytest.raises(ValueError, match=f"{game} has no mirrored seats .*: mirror=True is for {listed}$"):
            octax_core.make_multi(game, mirror=True)
    with pytest.raises(ValueError, match="Pong has no mirrored seats"):
        octax_core.make("Pong", mirror=True)
    with pytest.raises(ValueError, match=r"two-player env: octax_core.make_multi\('Cycles', mirror=True\)"):
        octax_core.make("Cycles", mirror=True)
    with pytest.raises(ValueError, match="a mix is one-player"):
        octax_core.make_mix(["Cycles", "Cycles1"], mirror=True)
    with pytest.raises(ValueError, match="mirror must be"):
        octax_core.make_multi("Cycles", mirror="yes")


def test_the_tables_players_play_the_same_game_in_a_mirrored_env(cycles):
    """The scripted bot answers in the game's actions; in a mirrored env seat 1's answer is mapped
    into its mirrored view (`make_player(..., mirrored=True)`), so the bots on both seats play the
    same game, machine for machine, with and without mirroring; unmapped, seat 1's left and right
    swap and the game is another. (A random player draws over the permuted view: an equally random,
    different game.)"""
    from octax_core.env.players import make_player

    def play(mirror, mapped, steps=60):
        env, params, reset, step = cycles[mirror]
        bot = make_player("scripted", env.spec, env.mirrored and mapped)
        both = jax.jit(lambda key, state: jnp.stack([bot(None, key, None, state, jnp.int32(seat), None)
                                                     for seat in (0, 1)]))
        states = [reset(key, params)[1] for key in jax.random.split(jax.random.key(3), N)]
        registers = []
        for t in range(steps):
            keys = jax.random.split(jax.random.key(100 + t), N)
            states = [step(key, state, both(key, state), params)[1] for key, state in zip(keys, states)]
            registers.append(np.stack([np.asarray(state.machine.V) for state in states]))
        return np.stack(registers)

    plain = play(False, True)
    np.testing.assert_array_equal(play(True, True), plain)
    assert not np.array_equal(play(True, False), plain)
    with pytest.raises(ValueError, match="declares no mirror image"):
        make_player("scripted", get_spec("Paddles"), mirrored=True)
