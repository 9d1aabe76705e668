"""Games group 2 through the env API: Missile, Rocket, Submarine, Tank, UFO, Airplane, Deep8,
ShootingStars, FlightRunner and Spacejam.

All ten games run in one compiled program (a mix: tests/core_games/game_harness.py), twice, 16
envs per game, without autoreset (an ended env stands still, so its terminal registers stay
readable):

* a scripted rollout: the first envs follow the game's `Plan` (a held action, or a closed-loop
  policy written against the game's registers and RAM), the rest take no-ops;
* a random rollout: 16 envs, 1,500 steps of uniform random actions.

The tests then read the recorded rewards, flags, scores, lives, registers and 16 bytes of RAM
(`RAM_WATCH`). The step bounds below are measured values (noted beside each) plus a margin.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from game_harness import Harness, N, Plan, assert_episode_adds_up

import octax_core
from octax_core.emulator.state import MEMORY_OFFSET

GAMES = ("Missile", "Rocket", "Submarine", "Tank", "UFO", "Airplane", "Deep8", "ShootingStars",
         "FlightRunner", "Spacejam")
RAM_WATCH = {"Tank": 0x212, "Deep8": 0x256}  # 16 bytes recorded per step; default 0x200

# Missile, one frame per step: the steps at which key 8 is pressed to hit all 8 targets with
# missiles to spare. Found by a greedy search (the first press that hits, shot after shot).
MISSILE_ALL_TARGETS = (27, 102, 174, 241, 304, 364, 419, 498)


def _v(machine, i):
    return machine.V[i].astype(jnp.int32)


def _deep8_greedy(machine):
    """Parks the boat (x = VA) over the highest squid and sinks a bomb (VE = 1 while sinking, VD
    its row) until it is just above it, then lets go to detonate. Squid records (countdown, x, y)
    sit at RAM 0x256; a squid is up when its countdown is 0. Actions: 1 left, 2 bomb, 3 right."""
    squid = jax.lax.dynamic_slice(machine.memory, (MEMORY_OFFSET + 0x256,), (12,))
    squid = squid.astype(jnp.int32).reshape(4, 3)
    up = (squid[:, 0] == 0) & (squid[:, 2] > 8) & (squid[:, 2] < 32)
    target = squid[jnp.argmin(jnp.where(up, squid[:, 2], 99))]
    boat, bomb_row, bomb = _v(machine, 10), _v(machine, 13), _v(machine, 14)
    steer = jnp.where(boat > target[1] + 2, 1, jnp.where(boat < target[1] - 2, 3, 2))
    sink = jnp.where(bomb_row + 6 < target[2], 2, 0)
    return jnp.where(~up.any(), 0, jnp.where(bomb == 0, steer, jnp.where(bomb == 1, sink, 0)))


PLANS = {
    "Missile": Plan(200, (0, 1)),
    "Rocket": Plan(400, (0, 1, 1, 1, 1, 1, 1, 1)),
    "Submarine": Plan(700, (0, 1)),
    "Tank": Plan(100, (0, 2, 4, 3)),
    "UFO": Plan(700, (0, 1, 2, 3)),
    "Airplane": Plan(500, (0, 1)),
    "Deep8": Plan(400, (0, "policy", "policy", "policy", "policy", 1, 3), _deep8_greedy),
    "ShootingStars": Plan(200, (0, 1, 2, 3, 4, 3, 3, 3)),
    "FlightRunner": Plan(300, (0, 1, 2, 3, 4)),
    "Spacejam": Plan(500, (0, 1, 2, 3, 4)),
}


HARNESS = Harness(PLANS, autoreset=False, ram_watch=RAM_WATCH)
_scripted, _random, _reset = HARNESS.scripted, HARNESS.random, HARNESS.reset_env0
_assert_episode_adds_up = assert_episode_adds_up


@pytest.fixture(scope="module")
def rom_dir(octax_rom_dir) -> str:
    return str(octax_rom_dir)


# ---- (1) the start-up reaches gameplay, and the game answers its keys ------------------------

def test_missile_reset(rom_dir):
    screen, V, _ = _reset("Missile", rom_dir)
    assert (V[5], V[6], V[7]) == (8, 10, 0)  # targets, missiles, points
    assert screen[1, 2:64:8].all() and screen[0:4].sum() == 8 * 8  # all 8 targets drawn
    assert not screen[4:].any()  # the launcher is between its erase and redraw


def test_rocket_reset(rom_dir):
    screen, V, _ = _reset("Rocket", rom_dir)
    assert (V[1], V[2]) == (0, 1)  # no hit yet, the first rocket on the pad
    assert screen[26:32, V[7]:V[7] + 5].sum() >= 10  # the rocket at its random column
    assert screen[27:32, 56:60].sum() == 14  # the score digit 0


def test_submarine_reset(rom_dir):
    screen, V, _ = _reset("Submarine", rom_dir)
    assert (V[7], V[8]) == (0, 25)
    assert screen[0:5, 0:14].sum() == 3 * 14 and screen[0:5, 50:64].sum() > 30  # "000" and "025"
    assert screen[6:9, 56:64].any() and screen[30:32].any()  # the ship and the large submarine


def test_tank_reset(rom_dir):
    screen, V, _ = _reset("Tank", rom_dir)
    assert (V[6], V[14]) == (25, 0)  # bombs, points
    assert screen[17:22, 12:18].sum() > 20  # the tank


def test_ufo_reset(rom_dir):
    screen, V, _ = _reset("UFO", rom_dir)
    assert (V[7], V[8]) == (0, 15)
    assert screen[27:32, 0:14].sum() == 3 * 14 and screen[27:32, 50:64].sum() > 30  # "000" and "015"
    assert screen[28:32, 29:34].sum() == 11  # the launcher


def test_airplane_reset(rom_dir):
    screen, V, state = _reset("Airplane", rom_dir)
    assert (V[11], V[12]) == (4, 1) and float(state.score[0]) == -5  # -(VB + VC)
    assert int(state.machine.pc[0]) not in range(0x20E, 0x21C)  # past the level's opening pause
    assert screen[25, ::2].all()  # the ground
    assert screen[2:4, 0:5].sum() == 6  # the player's plane, top left


def test_deep8_reset(rom_dir):
    screen, V, _ = _reset("Deep8", rom_dir)
    assert (V[11], V[9], V[10]) == (1, 0, 32)  # afloat, no squid destroyed, the boat in the middle
    assert screen[7:9].sum() == 16 * 2 + 16 * 3  # the waves
    assert screen[1:6, 32:40].sum() > 20 and screen[1:6, 49:64].sum() == 3 * 14  # the boat, "000"


def test_shooting_stars_reset(rom_dir):
    screen, V, _ = _reset("ShootingStars", rom_dir)
    assert V[0] == 0
    assert screen[14:20, 24:32].sum() == 4 + 6 + 8 + 8 + 6 + 4  # the big ball
    assert screen[V[4]:V[4] + 3].sum() >= 18  # the player's ball at its random row


def test_flight_runner_reset(rom_dir):
    screen, V, _ = _reset("FlightRunner", rom_dir)
    assert V[5] == 0 and V[7] == 9  # the start-up already scrolled 9 loops
    assert screen[3].all() and screen[28].all()  # ceiling and floor
    assert screen[14:17, 4:9].sum() == 4 + 2 + 4  # the ship


def test_spacejam_reset(rom_dir):
    screen, V, _ = _reset("Spacejam", rom_dir)
    assert (V[9], V[10], V[12]) == (1, 2, 56)  # the turn's point, 2 ships left, an obstacle at the right
    assert screen[0].all() and screen[31].all()  # ceiling and floor
    assert screen[14:17, 10:15].sum() == 4 + 2 + 4  # the ship


@pytest.mark.parametrize("game_id, where, index, lower_env, higher_env, step", [
    ("Tank", "ram", 3, 1, 2, 10),  # tank column: key 4 left vs key 6 right
    ("Deep8", "V", 10, 5, 6, 10),  # boat column: key 7 left vs key 9 right
    ("ShootingStars", "V", 4, 1, 2, 5),  # ball row: key 2 up vs key 8 down
    ("ShootingStars", "V", 3, 3, 4, 5),  # ball column: key 4 left vs key 6 right
    ("FlightRunner", "V", 13, 1, 3, 5),  # ship row: key 5 up vs key 8 down
    ("FlightRunner", "V", 14, 2, 4, 5),  # ship column: key 7 left vs key 9 right
    ("Spacejam", "V", 13, 1, 2, 12),  # ship row: key 5 up vs key 8 down (one move per ~11 steps)
    ("Spacejam", "V", 14, 3, 4, 12),  # ship column: key 7 left vs key 9 right
])
def test_action_keys_move_the_player(rom_dir, game_id, where, index, lower_env, higher_env, step):
    values = getattr(_scripted(game_id, rom_dir), where)[:, :, index]
    moved = (values[step] - values[0]).astype(np.int8)  # start positions may be random; V wraps
    assert moved[lower_env] < 0 < moved[higher_env]


# ---- (2) the score moves when it should ----------------------------------------------------

@pytest.mark.parametrize("game_id, env, bound, points", [
    ("Missile", 1, 40, {5}),  # key 8 held; measured: 31
    ("Rocket", 1, 150, {1}),  # key F held; measured: 111 (25-111 over envs 1-7)
    ("Submarine", 1, 300, {5, 10}),  # key 5 held; measured: 232
    ("UFO", 2, 120, {5, 15}),  # key 5 held; measured: 73
    ("ShootingStars", 3, 80, {-1, 1}),  # key 4 held, into the big ball across the wrap; measured: 53
])
def test_holding_the_key_scores(rom_dir, game_id, env, bound, points):
    run = _scripted(game_id, rom_dir)
    first = run.first_reward(env)
    assert first is not None and first < bound
    assert set(np.unique(run.reward[:, env])) <= {0.0} | points
    assert not run.reward[:, 0].any()  # no key, no points


def test_rocket_ends_as_the_ninth_rocket_appears(rom_dir):
    """The paper's V2 == 9 fires as the 9th rocket is placed on the pad: the episode ends on that
    step, before the ROM's end-of-game halt (pc 0x214), so only 8 rockets fly."""
    scripted, random = _scripted("Rocket", rom_dir), _random("Rocket", rom_dir)
    for run, envs in ((scripted, range(1, 8)), (random, range(N))):
        for i in envs:
            end = run.first_end(i)
            assert end is not None and end == int(np.argmax(run.V[:, i, 2] == 9))  # measured: 238-305
            assert run.V[end - 1, i, 2] == 8 and run.pc[end, i] != 0x214
            assert run.score[end, i] <= 8  # measured: 2-7 hits
    assert not scripted.terminated[:, 0].any() and (scripted.V[:, 0, 2] == 1).all()  # no launch, no end


def test_tank_bombs_hit_under_random_play(rom_dir):
    run = _random("Tank", rom_dir)
    assert run.reward.sum() >= 50  # measured: 110 (11 hits)
    assert set(np.unique(run.reward)) <= {0.0, 10.0}


def test_tank_random_games_end_as_v6_reaches_0(rom_dir):
    """The paper's V6 == 0 ends the episode on the step the last bomb leaves the tank, before the
    ROM's end-of-game halt (pc 0x394): that bomb's hit is never rewarded."""
    run = _random("Tank", rom_dir)
    for i in range(N):
        end = run.first_end(i)
        assert end is not None and end < 1100  # measured: 595-974 steps
        assert run.V[end, i, 6] == 0 and run.V[:end, i, 6].min() >= 1  # the first step with no bombs
        assert run.pc[end, i] != 0x394


def test_airplane_levels_cost_and_hits_pay(rom_dir):
    run = _scripted("Airplane", rom_dir)  # key 8 held: bombs reach the ground on levels 1-4, then hit
    first_down, first_up = run.first_reward(1, -1), run.first_reward(1)
    assert first_down < 40 and run.V[first_down, 1, 12] == 2  # measured: 31, level 2
    assert first_up < 300 and run.lives[first_up, 1] == 3  # measured: 274, a plane hit
    assert set(np.unique(run.reward)) <= {-1.0, 0.0, 1.0}


def test_deep8_greedy_bomber_destroys_squid(rom_dir):
    run = _scripted("Deep8", rom_dir)
    for i in (1, 2, 3, 4):
        assert run.reward[:, i].sum() >= 2  # measured: 12, 10, 12, 4 squid
    assert set(np.unique(run.reward)) <= {0.0, 1.0}


def test_flight_runner_scores_each_loop(rom_dir):
    run = _scripted("FlightRunner", rom_dir)
    end = run.first_end(0)  # no-op: the walls never close in before V7 tops out
    assert run.reward[:end + 1, 0].sum() == 255 - 9
    assert set(np.unique(run.reward[:end + 1, 0])) <= {0.0, 1.0}


def test_spacejam_scores_over_time(rom_dir):
    run = _random("Spacejam", rom_dir)
    assert run.reward.max() >= 3  # an obstacle passed, or the +6 speed-up bonus
    assert set(np.unique(run.reward)) <= {0.0, 1.0, 3.0, 4.0, 6.0, 7.0}


# ---- (3) every game ends under some policy, within a stated bound ---------------------------

@pytest.mark.parametrize("game_id, env, bound, final_score, start_score", [
    ("Missile", 1, 160, (25, 25), 0),  # key 8 held; measured: 142, 5 hits
    ("Rocket", 1, 320, (1, 8), 0),  # key F held, to the 9th rocket's arrival; measured: 266 (249-281)
    ("Submarine", 1, 700, (5, 250), 0),  # key 5 held; measured: 650
    ("UFO", 2, 700, (5, 225), 0),  # key 5 held; measured: 634
    ("Airplane", 1, 450, (-5, -5), -5),  # key 8 held; measured: 424, 4 levels up and 4 planes hit
    ("Deep8", 0, 60, (0, 0), 0),  # no-op: the first squid reaches the boat; measured: 46
    ("FlightRunner", 0, 300, (255, 255), 9),  # no-op, V7 tops out; measured: 283
    ("FlightRunner", 1, 30, (9, 30), 9),  # key 5 held, into the ceiling; measured: 14
    ("Spacejam", 0, 500, (2, 20), 1),  # no-op; measured: 248
])
def test_episode_ends_within_bound(rom_dir, game_id, env, bound, final_score, start_score):
    run = _scripted(game_id, rom_dir)
    end = run.first_end(env)
    assert end is not None and end < bound
    assert final_score[0] <= run.score[end, env] <= final_score[1]
    _assert_episode_adds_up(run, env, end, start_score)
    assert not run.truncated[:end + 1, env].any()


def test_flight_runner_crash_raises_v5(rom_dir):
    run = _scripted("FlightRunner", rom_dir)
    end = run.first_end(1)
    assert run.V[end, 1, 5] == 255 and run.V[end, 1, 7] < 255


def test_spacejam_ends_as_the_last_ship_takes_off(rom_dir):
    run = _scripted("Spacejam", rom_dir)
    end = run.first_end(0)
    assert run.lives[end, 0] == 0 and set(run.lives[:end, 0]) == {2, 1}
    assert run.score[end, 0] == 2  # the third turn's point comes after VA drops: never paid


def test_missile_ends_when_all_targets_are_hit(rom_dir):
    """With missiles to spare: the ROM halts with V5 == 0 and V6 > 0 (the paper tests V6 only)."""
    env, params = octax_core.make("Missile", rom=rom_dir, frames_per_step=1)
    actions = np.zeros(560, np.int32)  # measured: the 8th hit lands at step 548
    actions[list(MISSILE_ALL_TARGETS)] = 1

    def body(state, action):
        _, state, reward, terminated, _, _ = env.step(jax.random.key(0), state, action, params)
        return state, (reward, terminated, state.machine.V)

    _, state = env.reset(jax.random.key(0), params)
    _, (reward, terminated, V) = jax.jit(lambda s, a: jax.lax.scan(body, s, a))(state, jnp.asarray(actions))
    end = int(np.argmax(np.asarray(terminated)))
    assert np.asarray(terminated).any() and np.asarray(reward).sum() == 40
    assert (int(V[end, 5]), int(V[end, 6])) == (0, 3)


# ---- (4) random play -------------------------------------------------------------------------

REWARD_VALUES = {
    "Missile": {0, 5}, "Rocket": {0, 1}, "Submarine": {0, 5, 10}, "Tank": {0, 10}, "UFO": {0, 5, 15},
    "Airplane": {-1, 0, 1, 4}, "Deep8": {0, 1}, "ShootingStars": {-1, 0, 1}, "FlightRunner": {0, 1},
    "Spacejam": {0, 1, 3, 4, 6, 7},
}


@pytest.mark.parametrize("game_id", GAMES)
def test_random_play(rom_dir, game_id):
    run = _random(game_id, rom_dir)
    assert np.isfinite(run.reward).all()
    assert set(np.unique(run.reward).astype(int)) <= REWARD_VALUES[game_id]
    assert not run.truncated.any()  # every bound is above 1,500 steps
    if game_id == "ShootingStars":
        assert not run.terminated.any()
    else:
        assert run.terminated.any()


def test_shooting_stars_never_ends(rom_dir):
    run = _scripted("ShootingStars", rom_dir)
    assert not run.terminated.any() and not run.truncated.any()
    assert (run.score >= 0).all()  # the cap hides V0's pass through 255
