"""The rollout harness shared by the per-game env tests (tests/core_games/test_games_group*.py).

A `Harness` is built once per test module from the module's scripted `Plan`s and two switches:
`autoreset` (score and lives are then read from `info["final_info"]`, the values of the episode a
step belonged to, else from `info`) and `ram_watch` (game id -> the RAM address of the 16 bytes
recorded per step; 0x200 for games not listed).

All the module's games run in one compiled program: a mix (`octax_core.make_mix`, docs/mix.md),
where the game is data, so the module compiles one batched reset and one scan of `CHUNK` steps
instead of two programs per game. Env `g * N + i` of the batch plays game `g`, reset with game `g`
from the key `make(game)`'s env `i` was reset with, so it plays exactly what `make(game)` plays
from the same keys and actions (the mix's exactness: tests/core_env/test_mix.py, and every game
in test_mix_every_game.py, slow). With autoreset, an ended episode restarts on the env's own game
(`PinnedMix`: the mix would draw one from its weights); every rollout checks that no env ever
changed game. Each module's batch is run twice, `N` envs per game:

* `scripted`: the first envs of each game follow the game's `Plan`, the rest take no-ops (the
  batch runs for the longest plan; each game's rollout is cut to its own plan's steps);
* `random`: `RANDOM_STEPS` steps of uniform random actions over each game's own actions.

Imported by the test modules as `from game_harness import ...` (pytest's rootdir-prepend import
mode puts tests/core_games on sys.path).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Mapping

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from octax_core.emulator.state import MEMORY_OFFSET
from octax_core.env.games import get_spec
from octax_core.env.mix import MixEnv

N = 16  # envs per game
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

    def actions(self, steps: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(actions (steps, N) int32, use_policy (N,) bool); `steps` (>= self.steps) extends the plan."""
        steps = self.steps if steps is None else steps
        actions = np.zeros((steps, N), np.int32)
        use_policy = np.zeros(N, bool)
        for i, how in enumerate(self.envs):
            if how == "policy":
                use_policy[i] = True
            elif isinstance(how, str):
                replay = np.array([int(c) for c in how], np.int32)
                actions[:, i] = np.concatenate([replay, np.full(steps - len(replay), self.replay_then, np.int32)])
            else:
                actions[:, i] = np.resize(np.array(how, np.int32), steps)
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
    """The reset keys of a game's N envs (each game of the batch uses the same N)."""
    return jax.vmap(lambda i: jax.random.fold_in(jax.random.key(0), i))(jnp.arange(N))


def assert_episode_adds_up(rollout: Rollout, i: int, end: int, start_score: float = 0.0):
    """The rewards up to the end of env i's first episode sum to its final score."""
    assert rollout.reward[:end + 1, i].sum() == pytest.approx(rollout.score[end, i] - start_score)


class PinnedMix(MixEnv):
    """A mix whose autoreset restarts an env on its own game: `Env._restart_where` with the reset
    given the ended episode's game, which draws the start as `make(game)`'s autoreset does."""

    def _restart_where(self, operands, inputs):
        (obs, state), (key, mask, params) = operands, inputs
        fresh = self.reset_env(key, params, game=state.game)
        return jax.tree.map(lambda new, old: jnp.where(mask, new, old), fresh, (obs, state))


class Harness:
    """Compiled rollouts of one test module's games; every result is cached per rom_dir."""

    def __init__(self, plans: Mapping[str, Plan], *, autoreset: bool, ram_watch: Mapping[str, int] | None = None):
        self.plans = dict(plans)
        self.games = tuple(plans)
        self.autoreset = autoreset
        self.ram_watch = dict(ram_watch or {})
        self.compiled = functools.cache(self._compile)
        self._scripted_all = functools.cache(self._scripted_batch)
        self._random_all = functools.cache(self._random_batch)

    def index(self, game_id: str) -> int:
        return self.games.index(game_id)

    def envs(self, game_id: str) -> slice:
        """The batch's envs that play `game_id`."""
        g = self.index(game_id)
        return slice(g * N, (g + 1) * N)

    def _compile(self, rom_dir: str):
        """The mix and its jitted batched reset and chunk runner, one compile each for all games:
        (env, params, reset(params) -> (obs, state), run(state, actions, use_policy, key))."""
        specs = [get_spec(game) for game in self.games]
        env = PinnedMix(specs, None, dict(autoreset=self.autoreset), [rom_dir] * len(specs))
        params = env.default_params
        games = jnp.repeat(jnp.arange(len(self.games), dtype=jnp.int32), N)
        each = jnp.tile(jnp.arange(N), len(self.games))  # env g * N + i: the game's env i
        keys = reset_keys()[each]
        watch = jnp.array([MEMORY_OFFSET + self.ram_watch.get(g, DEFAULT_RAM_WATCH) for g in self.games], jnp.int32)
        policies = [self.plans[g].policy or (lambda machine: jnp.int32(0)) for g in self.games]
        autoreset = self.autoreset
        step = jax.vmap(env.step, in_axes=(0, 0, 0, None))

        def reset(params):
            return jax.vmap(lambda k, g: env.reset(k, params, game=g))(keys, games)

        def run(state, actions, use_policy, key):
            def body(state, xs):
                actions, step_key = xs
                chosen = jax.vmap(lambda g, m: jax.lax.switch(g, policies, m).astype(jnp.int32))(games, state.machine)
                actions = jnp.where(use_policy, chosen, actions)
                step_keys = jax.random.split(step_key, N)[each]  # as make(game)'s env i steps
                _, state, reward, terminated, truncated, info = step(step_keys, state, actions, params)
                episode = info["final_info"] if autoreset else info
                machine = state.machine
                ram = jax.vmap(lambda memory, at: jax.lax.dynamic_slice_in_dim(memory, at, 16))(
                    machine.memory, watch[games])
                flags = (reward, terminated, truncated, episode["score"], episode["lives"])
                return state, (*flags, machine.V, ram, machine.pc, state.game)
            return jax.lax.scan(body, state, (actions, jax.random.split(key, CHUNK)))

        return env, params, jax.jit(reset), jax.jit(run)

    def rollout(self, rom_dir: str, actions: np.ndarray, use_policy: np.ndarray, seed: int) -> Rollout:
        """Runs `actions` (T, games * N) from reset in whole chunks; chunk c steps with key(seed + c)."""
        _, params, reset, run = self.compiled(rom_dir)
        _, state = reset(params)
        outs = []
        for c in range(len(actions) // CHUNK):
            chunk = jnp.asarray(actions[c * CHUNK:(c + 1) * CHUNK])
            state, out = run(state, chunk, jnp.asarray(use_policy), jax.random.key(seed + c))
            outs.append(jax.tree.map(np.asarray, out))
        *fields, games = (np.concatenate(parts) for parts in zip(*outs))
        assert (games == np.repeat(np.arange(len(self.games)), N)).all(), "an env changed game"
        return Rollout(*fields)

    def run_chunk(self, rom_dir: str, state, actions: np.ndarray) -> Rollout:
        """One chunk from `state` (of the whole batch) with `actions` (CHUNK, games * N), key(0)."""
        _, _, _, run = self.compiled(rom_dir)
        _, out = run(state, jnp.asarray(actions), jnp.zeros(len(self.games) * N, bool), jax.random.key(0))
        return Rollout(*jax.tree.map(np.asarray, out[:-1]))

    def cut(self, rollout: Rollout, game_id: str, steps: int) -> Rollout:
        """The game's N envs over the first `steps` steps."""
        return Rollout(*(np.asarray(field)[:steps, self.envs(game_id)] for field in dataclasses.astuple(rollout)))

    def _scripted_batch(self, rom_dir: str) -> Rollout:
        steps = -(-max(plan.steps for plan in self.plans.values()) // CHUNK) * CHUNK
        actions, use_policy = zip(*(self.plans[g].actions(steps) for g in self.games))
        return self.rollout(rom_dir, np.concatenate(actions, axis=1), np.concatenate(use_policy), seed=0)

    def _random_batch(self, rom_dir: str) -> Rollout:
        # each game's actions are what its own rollout of N envs drew (one generator per game)
        actions = [np.random.default_rng(1).integers(0, len(get_spec(g).action_keys) + 1, (RANDOM_STEPS, N),
                                                     dtype=np.int32) for g in self.games]
        return self.rollout(rom_dir, np.concatenate(actions, axis=1), np.zeros(len(self.games) * N, bool), seed=10_000)

    def scripted(self, game_id: str, rom_dir: str) -> Rollout:
        return self.cut(self._scripted_all(rom_dir), game_id, self.plans[game_id].steps)

    def random(self, game_id: str, rom_dir: str) -> Rollout:
        return self.cut(self._random_all(rom_dir), game_id, RANDOM_STEPS)

    def reset_env0(self, game_id: str, rom_dir: str):
        """The game's env 0 after reset: (screen (32, 64) bool, registers as ints, EnvState of its N envs)."""
        _, params, reset, _ = self.compiled(rom_dir)
        obs, state = reset(params)
        state = jax.tree.map(lambda leaf: leaf[self.envs(game_id)], state)
        g = self.index(game_id) * N
        return np.asarray(obs[g, -1]).astype(bool), np.asarray(state.machine.V[0]).astype(int), state
