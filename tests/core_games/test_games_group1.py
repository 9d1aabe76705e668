"""Games group 1 through the env API: Pong, Brix, Tetris, Blinky, Worm, Squash, VerticalBrix,
WipeOff and Filter.

All nine games run in one compiled program (a mix: tests/core_games/game_harness.py), twice,
16 envs per game, with autoreset:

* a scripted rollout: the first envs follow the game's `Plan` (a held action, a cycle of
  actions, a closed-loop policy written against the game's registers, or a replayed action
  string), the rest take no-ops;
* a random rollout: 16 envs, 1,500 steps of uniform random actions.

The tests then read the recorded rewards, flags, scores, lives and registers. The step bounds
below are measured values (noted beside each) plus a margin.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from game_harness import CHUNK, Harness, N, Plan, Rollout, assert_episode_adds_up

from octax_core.env.games import get_spec

GAMES = ("Pong", "Brix", "Tetris", "Blinky", "Worm", "Squash", "VerticalBrix", "WipeOff", "Filter")

# Tetris: env 0 (reset key fold_in(key(0), 0)) clears its first line at the last step of this string.
# Found by a seeded random search (drop-biased actions), then simplified to mostly drops (4).
TETRIS_LINE = (
    "34444442444442444244441444444424444244444441444444041444444444444444444444244443444444442444"
    "34444344444344444404444444444444424444344444344443444344444244444244444344424444244414442344"
    "44434444444444444444444444444444034422444434442244443444442444224433444442444433442444144444"
    "4412444444444444444444444444444431444434444344444344443344444444444444444444444444444444"
)


def _v(machine, i):
    return machine.V[i].astype(jnp.int32)


def _worm_greedy(machine):
    """Steers the head (VA, VB) at the food (VC, VD) without ever reversing (V9: 0 right, 2 up,
    4 left, 6 down). Actions: 1 up, 2 down, 3 left, 4 right."""
    head_x, head_y, food_x, food_y, heading = (_v(machine, i) for i in (10, 11, 12, 13, 9))
    horizontal = jnp.where(head_x < food_x - 1, 4, jnp.where(head_x > food_x + 4, 3, 0))
    vertical = jnp.where(head_y < food_y - 2, 2, jnp.where(head_y > food_y + 3, 1, 0))
    want = jnp.where(horizontal != 0, horizontal, vertical)
    reverse = jnp.array([3, 2, 4, 1])[heading // 2 % 4]
    sideways = jnp.where(heading // 2 % 2 == 0, jnp.where(vertical == 1, 1, 2), jnp.where(horizontal == 3, 3, 4))
    return jnp.where(want == reverse, sideways, want)


def _filter_greedy(machine):
    """Keeps the 6-pixel paddle (x = VB) under the drop (x = V8). Actions: 1 left, 2 right."""
    drop, paddle = _v(machine, 8), _v(machine, 11)
    return jnp.where(drop < paddle + 1, 1, jnp.where(drop > paddle + 4, 2, 0))


PLANS = {
    "Pong": Plan(1000, (0, 1, 2)),
    "Brix": Plan(600, (0, 1, 2)),
    "Tetris": Plan(800, (TETRIS_LINE, 4, 2, 3), replay_then=4),  # after the line: drops
    "Blinky": Plan(600, (0, 4, 3, 1)),
    "Worm": Plan(400, (0, "policy", "policy", "policy", "policy", "policy", "policy", 1, 2), _worm_greedy),
    "Squash": Plan(400, (0, (1, 0), (2, 0))),
    "VerticalBrix": Plan(400, (0, 1, 2)),
    "WipeOff": Plan(1200, (0, (1, 0), (2, 0))),
    "Filter": Plan(3000, (0, "policy", "policy", "policy", 1, 2), _filter_greedy),
}


HARNESS = Harness(PLANS, autoreset=True)
_scripted, _random, _reset = HARNESS.scripted, HARNESS.random, HARNESS.reset_env0
_assert_episode_adds_up = assert_episode_adds_up


@pytest.fixture(scope="module")
def rom_dir(octax_rom_dir) -> str:
    return str(octax_rom_dir)


def _run_with_register(game_id: str, rom_dir: str, register: int, value: int, action) -> Rollout:
    """One chunk from reset with V[register] = value in the game's envs, `action` (an int, or a
    tuple cycled) in all of them; the episode's score starts from the changed state."""
    _, params, reset, _ = HARNESS.compiled(rom_dir)
    _, state = reset(params)
    envs = HARNESS.envs(game_id)
    machine = state.machine.replace(V=state.machine.V.at[envs, register].set(value))
    score = jax.vmap(get_spec(game_id).score_fn)(machine).astype(jnp.float32)
    own = jnp.zeros(len(GAMES) * N, bool).at[envs].set(True)
    state = state.replace(machine=machine, score=jnp.where(own, score, state.score))
    actions = np.zeros((CHUNK, len(GAMES) * N), np.int32)
    actions[:, envs] = np.resize(np.array(action, np.int32), CHUNK)[:, None]
    return HARNESS.cut(HARNESS.run_chunk(rom_dir, state, actions), game_id, CHUNK)


# ---- (1) the start-up reaches gameplay, and the game answers its keys ------------------------

def test_pong_reset(rom_dir):
    screen, V, state = _reset("Pong", rom_dir)
    assert V[14] == 0 and float(state.score[0]) == 0
    assert screen[12:18, 2].all() and screen[12:18, 63].all()  # both paddles, 6 pixels tall
    assert screen[0:5, 20:24].any() and screen[0:5, 41:45].any()  # the two score digits


def test_brix_reset(rom_dir):
    screen, V, _ = _reset("Brix", rom_dir)
    assert (V[14], V[5]) == (5, 0)
    assert [int(screen[row].sum()) for row in range(6, 18, 2)] == [48] * 6  # 6 rows of 16 bricks
    assert screen[31, 32:38].all() and screen[31].sum() == 6  # the paddle


def test_tetris_reset(rom_dir):
    screen, V, _ = _reset("Tetris", rom_dir)
    assert V[10] == 0 and V[1] != 2
    assert screen[:31, 26].all() and screen[:31, 37].all() and screen[31, 26:38].all()  # the well
    assert not screen[:31, 27:37].any()


def test_blinky_reset(rom_dir):
    screen, V, state = _reset("Blinky", rom_dir)
    assert V[6] == 0 and V[3] != 255 and float(state.score[0]) == 0
    assert screen[0, 0:31].all() and screen[0, 32:63].all() and screen[30, 0:25].all()  # the maze walls
    assert screen[2, 2:62:2].all()  # a row of pills


def test_worm_reset(rom_dir):
    screen, V, _ = _reset("Worm", rom_dir)
    assert V[5] == 0 and V[7] == 124  # V7 becomes 0 once play starts, 255 at game over
    assert screen[0, 1:59].all() and screen[1:31, 0].all() and screen[1:31, 58].all()  # the walls
    assert screen[14:17, 6:9].all()  # the worm's head


def test_squash_reset(rom_dir):
    screen, V, state = _reset("Squash", rom_dir)
    assert V[11] == 5 and float(state.score[0]) == 5
    assert screen[0].all() and screen[30].all() and screen[1:30, 62:64].all()  # three walls
    assert screen[V[4]:V[4] + 5, 0].all()  # the paddle at its random-drawn row


def test_vertical_brix_reset(rom_dir):
    screen, V, _ = _reset("VerticalBrix", rom_dir)
    assert (V[7], V[8], V[14]) == (3, 0, 70)  # lives, score, bricks left
    assert screen[16:21, 2].all()  # the paddle
    assert screen[1:31, 34:55].sum() > 400  # the wall of bricks


def test_wipe_off_reset(rom_dir):
    screen, V, _ = _reset("WipeOff", rom_dir)
    assert (V[7], V[6]) == (15, 0)
    assert screen[0:28].sum() == 112  # the spots
    assert screen[30, 32:40].all()  # the paddle


def test_filter_reset(rom_dir):
    screen, V, _ = _reset("Filter", rom_dir)
    assert (V[13], V[14]) == (7, 0)
    assert screen[6].all()  # the pipe
    assert screen[28, 29:35].all()  # the paddle


@pytest.mark.parametrize("game_id, register, lower_env, higher_env, step", [
    ("Pong", 11, 1, 2, 10),  # paddle row: key 1 up vs key 4 down
    ("Brix", 12, 1, 2, 10),  # paddle column: key 4 left vs key 6 right
    ("Tetris", 0, 2, 3, 15),  # piece column: key 5 left vs key 6 right
    ("Blinky", 8, 2, 1, 10),  # Blinky's column: key 7 left vs key 8 right
    ("Worm", 9, 7, 8, 5),  # heading: key 2 up (2) vs key 8 down (6)
    ("Squash", 4, 1, 2, 10),  # paddle row: taps of key 1 up vs key 4 down
    ("VerticalBrix", 9, 1, 2, 10),  # paddle row: key 1 up vs key 4 down
    ("WipeOff", 0, 1, 2, 20),  # paddle column: taps of key 4 left vs key 6 right
    ("Filter", 11, 4, 5, 3),  # paddle column: key 4 left vs key 6 right
])
def test_action_keys_move_the_player(rom_dir, game_id, register, lower_env, higher_env, step):
    V = _scripted(game_id, rom_dir).V
    assert V[step, lower_env, register] < V[step, higher_env, register]


# ---- (2) the score moves when it should ----------------------------------------------------

def test_pong_the_computer_scores_on_a_paddle_stuck_at_the_top(rom_dir):
    run = _scripted("Pong", rom_dir)
    assert run.first_reward(1, -1) < 150  # measured: 93
    assert set(np.unique(run.reward)) <= {-1.0, 0.0, 1.0}


def test_brix_a_brick_breaks_soon_after_the_serve(rom_dir):
    run = _scripted("Brix", rom_dir)
    assert run.first_reward(0) < 30  # measured: 16
    assert run.V[run.first_reward(0), 0, 5] == 1


def test_tetris_a_line_clears(rom_dir):
    run = _scripted("Tetris", rom_dir)
    assert run.first_reward(0) == len(TETRIS_LINE) - 1
    assert run.reward[len(TETRIS_LINE) - 1, 0] == 1 and run.V[len(TETRIS_LINE) - 1, 0, 10] == 1


def test_blinky_eats_pills(rom_dir):
    run = _scripted("Blinky", rom_dir)
    assert run.first_reward(1) < 5  # key 8 held; measured: 1
    assert run.reward[:, 1].sum() >= 3  # measured: 5 pills, then a wall


def test_blinky_the_score_is_v6_and_a_cleared_maze_drops_it_to_0(rom_dir):
    """The paper's score, V6, counts the current maze's pills; the ROM banks them (and the 100
    bonus) in RAM and zeroes V6 when the maze is cleared: one large negative reward."""
    run = _run_with_register("Blinky", rom_dir, 6, 246, 4)  # one pill short of the maze's 247; key 8
    last_pill, clear = run.first_reward(0), run.first_reward(0, -1)
    assert run.reward[last_pill, 0] == 1 and run.V[last_pill, 0, 6] == 247
    assert clear is not None and clear - last_pill < 10  # measured: 4 steps after the last pill
    assert run.reward[clear, 0] == -247 and run.V[clear, 0, 6] == 0
    assert (run.score[:, 0] == run.V[:, 0, 6]).all() and not run.terminated[:, 0].any()


def test_worm_eats_food(rom_dir):
    run = _scripted("Worm", rom_dir)
    greedy = [i for i, how in enumerate(PLANS["Worm"].envs) if how == "policy"]
    eaten = [run.reward[:, i].sum() for i in greedy]
    assert sum(eaten) >= 20 and max(eaten) >= 5  # measured: 80 over 400 steps, first episodes 12, 6, 4, 3, 11, 0
    assert set(np.unique(run.reward)) <= {0.0, 1.0}


def test_squash_a_missed_ball_costs_one(rom_dir):
    run = _scripted("Squash", rom_dir)
    assert run.first_reward(1, -1) < 60  # measured: 45
    assert run.lives[run.first_reward(1, -1), 1] == 4


def test_squash_stalls_until_a_key_is_released(rom_dir):
    run = _scripted("Squash", rom_dir)  # env 0 never presses: the ROM waits (FX0A) after the first miss
    assert not run.terminated[:, 0].any() and not run.reward[:, 0].any() and (run.lives[:, 0] == 5).all()


def test_vertical_brix_a_brick_breaks(rom_dir):
    run = _scripted("VerticalBrix", rom_dir)
    assert run.first_reward(0) < 50  # measured: 33


def test_wipe_off_spots_are_wiped_after_a_serve(rom_dir):
    run = _scripted("WipeOff", rom_dir)
    assert run.first_reward(1) < 60 and run.first_reward(2) < 60  # measured: 34, 34
    assert not run.reward[:, 0].any() and (run.lives[:, 0] == 15).all()  # no key press, no serve


def test_filter_catches_drops(rom_dir):
    run = _scripted("Filter", rom_dir)
    for i in (1, 2, 3):  # the greedy paddle
        assert run.first_reward(i) < 40  # measured: 23-24
        assert run.reward[:300, i].sum() >= 8  # measured: 9-11
        assert run.lives[run.first_end(i), i] >= 1  # it wins (99 drops) with lives to spare


# ---- (3) every game ends under some policy, within a stated bound ---------------------------

@pytest.mark.parametrize("game_id, env, bound, final_score, final_lives", [
    ("Pong", 1, 1000, (-9, -1), None),  # key 1 held; measured: 749, 0-9
    ("Brix", 0, 170, (1, 95), 4),  # no-op, ends at the first lost ball; measured: 128, 11 bricks
    ("Brix", 1, 100, (0, 95), 4),  # key 4 held; measured: 64, 2 bricks
    ("Tetris", 1, 400, (0, 0), None),  # drop held; measured: 312
    ("Blinky", 0, 500, (0, 0), None),  # no-op; measured: 390
    ("Worm", 0, 60, (0, 1), None),  # no-op, into the right wall; measured: 42
    ("Squash", 1, 300, (0, 0), 0),  # taps of key 1; measured: 253
    ("VerticalBrix", 0, 350, (1, 69), 0),  # no-op; measured: 276
    ("WipeOff", 2, 1000, (1, 111), 0),  # taps of key 6; measured: 810, 30 spots
    ("Filter", 0, 250, (0, 98), 0),  # no-op; measured: 202
    ("Filter", 1, 2900, (99, 99), None),  # greedy, 99 drops caught; measured: 2567, 5 lives left
])
def test_episode_ends_within_bound(rom_dir, game_id, env, bound, final_score, final_lives):
    run = _scripted(game_id, rom_dir)
    end = run.first_end(env)
    assert end is not None and end < bound
    assert final_score[0] <= run.score[end, env] <= final_score[1]
    if final_lives is not None:
        assert run.lives[end, env] == final_lives
    start = 5.0 if game_id == "Squash" else 0.0
    _assert_episode_adds_up(run, env, end, start)
    assert not run.truncated[:end + 1, env].any()


@pytest.mark.parametrize("game_id, register, value, action", [
    ("Brix", 5, 95, 0),  # 95 bricks down, the serve breaks the last
    ("WipeOff", 6, 111, (2, 0)),  # 111 spots wiped, a serve (taps of key 6) wipes the last
])
def test_a_won_game_ends(rom_dir, game_id, register, value, action):
    run = _run_with_register(game_id, rom_dir, register, value, action)
    win = run.first_reward(0)
    assert win is not None and run.terminated[win, 0] and run.score[win, 0] == value + 1


def test_lives_count_down_one_at_a_time(rom_dir):
    # Brix ends on the paper's V14 == 4: at its first lost ball, with 4 of its 5 balls left
    for game_id, env, start, last in (("Brix", 0, 5, 4), ("VerticalBrix", 0, 3, 0), ("Filter", 0, 7, 0)):
        run = _scripted(game_id, rom_dir)
        lives = run.lives[:run.first_end(env) + 1, env]
        assert lives[0] == start and lives[-1] == last
        assert set(np.diff(lives)) <= {0, -1}


def test_brix_every_episode_is_one_ball(rom_dir):
    """Under the paper's V14 == 4, every episode ends as its first ball is lost (the ROM would
    serve 4 more): random play ends each episode with 4 lives and at most a few hundred steps."""
    run = _random("Brix", rom_dir)
    assert (run.lives[run.terminated] == 4).all()
    for i in range(N):
        ends = np.flatnonzero(run.terminated[:, i])
        assert len(ends) >= 10  # measured: 555 episodes over 16 envs, 30-39 per env
        assert np.diff(np.concatenate([[-1], ends])).max() < 340  # measured: 33-303 steps


# ---- (4) random play -------------------------------------------------------------------------

REWARD_VALUES = {
    "Pong": {-1, 0, 1}, "Brix": {0, 1}, "Tetris": {0, 1, 2, 3, 4}, "Worm": {0, 1}, "Squash": {-1, 0},
    "VerticalBrix": {0, 1}, "WipeOff": {0, 1}, "Filter": {0, 1},
    "Blinky": {0, 1, 4},  # pill, energy pill; V6 never holds the ghost bonuses (a maze's -247: out of reach)
}


@pytest.mark.parametrize("game_id", GAMES)
def test_random_play(rom_dir, game_id):
    run = _random(game_id, rom_dir)
    assert np.isfinite(run.reward).all()
    assert set(np.unique(run.reward).astype(int)) <= REWARD_VALUES[game_id]
    assert not run.truncated.any()  # every bound is above 1,500 steps
    if game_id != "Tetris":  # a random Tetris game lasts about 2,000 steps
        assert run.terminated.any()
