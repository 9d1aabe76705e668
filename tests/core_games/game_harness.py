"""The rollout harness shared by the per-game env tests (tests/games/test_games_group*.py).

A `Harness` is built once per test module from the module's scripted `Plan`s and two switches:
`autoreset` (make() with autoreset; score and lives are then read from `info["final_info"]`, the
values of the episode a step belonged to, else from `info`) and `ram_watch` (game id -> the RAM
address of the 16 bytes recorded per step; 0x200 for games not listed). Per game it compiles, once,
a jitted batched reset and a jitted scan of `CHUNK` batched steps (with the game's optional
closed-loop policy), and runs it twice, `N` envs each:

* `scripted`: the first envs follow the game's `Plan`, the rest take no-ops;
* `random`: `RANDOM_STEPS` steps of uniform random actions.

Imported by the test modules as `from game_harness import ...` (pytest's rootdir-prepend import
mode puts tests/games on sys.path).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Mapping

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.emulator.state import MEMORY_OFFSET

N = 16  # envs per rollout
CHUNK = 100  # steps per compiled scan
RANDOM_STEPS = 1500
DEFAULT_RAM_WATCH = 0x200


@dataclasses.dataclass(frozen=True)
class Plan:
    """The scripted rollout: `envs[i]` drives env i (an int: that action held; a tuple: cycled;
    a str: replayed digit by digit, then `replay_then` held; "policy": the closed-loop `policy`)."""

    steps: int
    envs: tuple
    policy: Callable | None = None
    replay_then: int = 0

    def actions(self) -> tuple[np.ndarray, np.ndarray]:
        """(actions (steps, N) int32, use_policy (N,) bool)."""
        actions = np.zeros((self.steps, N), np.int32)
        use_policy = np.zeros(N, bool)
        for i, how in enumerate(self.envs):
            if how == "policy":
                use_policy[i] = True
            elif isinstance(how, str):
                replay = np.array([int(c) for c in how], np.int32)
                actions[:, i] = np.concatenate([replay, np.full(self.steps - len(replay), self.replay_then, np.int32)])
            else:
                actions[:, i] = np.resize(np.array(how, np.int32), self.steps)
        return actions, use_policy


@dataclasses.dataclass(frozen=True)
class Rollout:
    """Per step t and env i: reward, terminated, truncated, score, lives (with autoreset: those of
    the episode the step belonged to, final values when it ended there), and the registers,
    watched RAM and pc after the step (without autoreset: frozen once the episode has ended)."""

    reward: np.ndarray  # (T, N) float32
    terminated: np.ndarray  # (T, N) bool
    truncated: np.ndarray  # (T, N) bool
    score: np.ndarray  # (T, N) float32
    lives: np.ndarray  # (T, N) int32
    V: np.ndarray  # (T, N, 16) uint8
    ram: np.ndarray  # (T, N, 16) uint8, from the harness's ram_watch
    pc: np.ndarray  # (T, N) uint16

    def first_end(self, i: int) -> int | None:
        ends = np.flatnonzero(self.terminated[:, i])
        return int(ends[0]) if len(ends) else None

    def first_reward(self, i: int, sign: int = 1) -> int | None:
        hits = np.flatnonzero(np.sign(self.reward[:, i]) == sign)
        return int(hits[0]) if len(hits) else None


def reset_keys():
    return jax.vmap(lambda i: jax.random.fold_in(jax.random.key(0), i))(jnp.arange(N))


def assert_episode_adds_up(rollout: Rollout, i: int, end: int, start_score: float = 0.0):
    """The rewards up to the end of env i's first episode sum to its final score."""
    assert rollout.reward[:end + 1, i].sum() == pytest.approx(rollout.score[end, i] - start_score)


class Harness:
    """Compiled per-game rollouts for one test module; every result is cached per (game, rom_dir)."""

    def __init__(self, plans: Mapping[str, Plan], *, autoreset: bool, ram_watch: Mapping[str, int] | None = None):
        self.plans = plans
        self.autoreset = autoreset
        self.ram_watch = dict(ram_watch or {})
        self.compiled = functools.cache(self._compile)
        self.scripted = functools.cache(self._scripted)
        self.random = functools.cache(self._random)

    def _compile(self, game_id: str, rom_dir: str):
        """make() plus the jitted batched reset and chunk runner; one compile each per game:
        (env, params, reset(keys, params), run(state, actions, use_policy, key))."""
        env, params = octax_core.make(game_id, rom=rom_dir, autoreset=self.autoreset)
        policy = self.plans[game_id].policy
        autoreset = self.autoreset
        watch = MEMORY_OFFSET + self.ram_watch.get(game_id, DEFAULT_RAM_WATCH)
        step = jax.vmap(env.step, in_axes=(0, 0, 0, None))

        def run(state, actions, use_policy, key):
            def body(state, xs):
                actions, step_key = xs
                if policy is not None:
                    actions = jnp.where(use_policy, jax.vmap(policy)(state.machine), actions)
                step_keys = jax.random.split(step_key, N)
                _, state, reward, terminated, truncated, info = step(step_keys, state, actions, params)
                episode = info["final_info"] if autoreset else info
                machine = state.machine
                ram = jax.lax.dynamic_slice_in_dim(machine.memory, watch, 16, axis=1)
                flags = (reward, terminated, truncated, episode["score"], episode["lives"])
                return state, (*flags, machine.V, ram, machine.pc)
            return jax.lax.scan(body, state, (actions, jax.random.split(key, CHUNK)))

        return env, params, jax.jit(jax.vmap(env.reset, in_axes=(0, None))), jax.jit(run)

    def rollout(self, game_id: str, rom_dir: str, actions: np.ndarray, use_policy: np.ndarray, seed: int) -> Rollout:
        """Runs `actions` (T, N) from reset in whole chunks; chunk c steps with key(seed + c)."""
        _, params, reset, run = self.compiled(game_id, rom_dir)
        _, state = reset(reset_keys(), params)
        outs = []
        for c in range(len(actions) // CHUNK):
            chunk = jnp.asarray(actions[c * CHUNK:(c + 1) * CHUNK])
            state, out = run(state, chunk, jnp.asarray(use_policy), jax.random.key(seed + c))
            outs.append(jax.tree.map(np.asarray, out))
        return Rollout(*(np.concatenate(parts) for parts in zip(*outs)))

    def _scripted(self, game_id: str, rom_dir: str) -> Rollout:
        actions, use_policy = self.plans[game_id].actions()
        return self.rollout(game_id, rom_dir, actions, use_policy, seed=0)

    def _random(self, game_id: str, rom_dir: str) -> Rollout:
        num_actions = self.compiled(game_id, rom_dir)[0].num_actions
        actions = np.random.default_rng(1).integers(0, num_actions, (RANDOM_STEPS, N), dtype=np.int32)
        return self.rollout(game_id, rom_dir, actions, np.zeros(N, bool), seed=10_000)

    def reset_env0(self, game_id: str, rom_dir: str):
        """Env 0 after reset: (screen (32, 64) bool, registers as ints, EnvState)."""
        _, params, reset, _ = self.compiled(game_id, rom_dir)
        obs, state = reset(reset_keys(), params)
        return np.asarray(obs[0, -1]).astype(bool), np.asarray(state.machine.V[0]).astype(int), state
