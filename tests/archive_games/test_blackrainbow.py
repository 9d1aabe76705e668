"""Black Rainbow: a navigator (breadth-first search over the world's doors, then over the room's
tiles) reaches the Motherlode in one world and ends the game; the clock costs a point a time unit."""

from collections import deque

import jax
import numpy as np

from archive_play import constant_policy, play, random_policy
from octax_core.emulator.state import MEMORY_OFFSET
from octax_core.env import make

WORLD, BOARD, ROOM = 0x6A4, 0x312, 0x703  # `world` (2 bytes a room), `board` (x * 8 + y), room x, y
MOTHERLODE, EYE_TILE = (3, 3), (7, 3)
MOVES = {"u": (0, -1, 1), "d": (0, 1, 2), "l": (-1, 0, 3), "r": (1, 0, 4)}  # dx, dy, action
ON_SIDE = {"l": lambda x, y: x == 0, "r": lambda x, y: x == 15, "u": lambda x, y: y == 0,
           "d": lambda x, y: y == 7}


def _doors(world, x, y):
    """The sides of room (x, y) with a door: its own byte has its right and down doors, its left
    and upper neighbours' bytes the others (`load-board`)."""
    own, left, up = (world[2 * (rx % 5 + 5 * (ry % 5))] for rx, ry in ((x, y), (x - 1, y), (x, y - 1)))
    return {"r": own & 3, "d": own & 12, "l": left & 3, "u": up & 12}


def _search(start, goal, neighbours):
    """The first step of a shortest path from start to a state goal() accepts; [] at a goal;
    None where no path exists."""
    previous, queue = {start: None}, deque([start])
    while queue:
        node = queue.popleft()
        if goal(node):
            path = []
            while previous[node]:
                node, step = previous[node]
                path.append(step)
            return path[::-1]
        for step, nxt in neighbours(node):
            if nxt not in previous:
                previous[nxt] = (node, step)
                queue.append(nxt)
    return None


class _Navigator:
    """Heads for the next room on a shortest door route to the Motherlode (giving up a side its
    room's tiles do not reach), steering the player's centre tile ((px + 2) / 8, (py + 2) / 8:
    where the ROM's collision probes look) along the room's free tiles; then onto the pupil."""

    def __init__(self):
        self.blocked, self.action = set(), 0

    def __call__(self, machine):
        if int(machine.sp) != 0:  # in a subroutine (a room being loaded): keep going
            return self.action
        memory = np.asarray(machine.memory[MEMORY_OFFSET:MEMORY_OFFSET + 0x1000]).astype(int)
        px, py = (int(v) for v in np.asarray(machine.V)[5:7])
        room, world = tuple(memory[ROOM:ROOM + 2]), memory[WORLD:WORLD + 50]
        board = memory[BOARD:BOARD + 128]
        here = ((px + 2) >> 3, (py + 2) >> 3)

        def tiles(tile):
            for dx, dy, action in MOVES.values():
                x, y = tile[0] + dx, tile[1] + dy
                if 0 <= x < 16 and 0 <= y < 8 and board[x * 8 + y] in (0, 24):  # empty or a gem
                    yield action, (x, y)

        def rooms(node):
            for side, (dx, dy, _) in MOVES.items():
                if _doors(world, *node)[side] and (node, side) not in self.blocked:
                    yield side, ((node[0] + dx) % 5, (node[1] + dy) % 5)

        if room == MOTHERLODE and here == EYE_TILE:  # onto the pupil, at about (60, 28)
            self.action = 4 if px < 59 else 3 if px > 61 else 2 if py < 27 else 1 if py > 29 else 0
            return self.action
        while True:
            if room == MOTHERLODE:
                side, goal = None, lambda tile: tile == EYE_TILE
            else:
                route = _search(room, lambda node: node == MOTHERLODE, rooms)
                if not route:
                    return 0
                side = route[0]
                goal = lambda tile: ON_SIDE[side](*tile)  # noqa: E731 (rebound per side)
            path = _search(here, goal, tiles)
            if path is not None or side is None:
                break
            self.blocked.add((room, side))
        self.action = path[0] if path else (MOVES[side][2] if side else 0)  # in the door: walk out
        return self.action


def test_a_navigator_reaches_the_motherlode():
    env, params = make("BlackRainbow")
    step = jax.jit(env.step)
    _, state = env.reset(jax.random.key(2), params)  # a world it crosses in about 375 steps
    navigate, rewards = _Navigator(), []
    for t in range(600):
        action = navigate(state.machine)
        _, state, reward, terminated, _, _ = step(jax.random.key(t), state, action, params)
        rewards.append(float(reward))
        if terminated:
            break
    assert terminated and len(rewards) < 500
    assert set(rewards) <= {-1.0, 0.0, 1.0, 2.0}
    assert -30 < sum(rewards) < 0  # the clock ran, at most a loop a frame


def test_the_clock_runs_while_nobody_moves():
    played = play("BlackRainbow", constant_policy(0), steps=600, num_envs=1)
    assert played.episodes_ended == 0 and set(played.rewards.ravel()) == {-1.0, 0.0}
    assert 30 <= -played.rewards.sum() <= 45  # a time unit every 64 loops, a loop a frame


def test_random_play_never_spikes():
    played = play("BlackRainbow", random_policy(5), steps=600, num_envs=2)
    assert played.rewards.min() >= -1 and played.rewards.max() <= 2
