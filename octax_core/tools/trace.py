"""Register traces: play a game and record V0..VF, the reward and episode ends at every step.

This is the recording half of the paper's "dynamic monitoring" (appendix, Score Detection
Methodology): watch the registers while the game is played and see which ones behave like a
score, a lives count or a game-over flag. `octax_core.tools.trace_rank` ranks the registers of a
`Trace`; `octax-gym trace` prints that ranking.

    trace = record_trace("Brix", steps=2000)                    # a registered game, its reward
    trace = record_trace("Brix", steps=2000, blind=True)        # the same, told nothing
    trace = record_trace(raw_rom_spec("game.ch8"), rom="game.ch8")   # a ROM with no spec

A `GameSpec` gives the trace a reward and a termination. Told nothing (`blind`, or a raw ROM),
episodes end only when the game stalls: the screen unchanged for `stall_steps` steps in a row,
as after a game's final jump-to-self or on a still game-over screen.
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.state import shown
from octax_core.env.environment import Env, EnvParams, make
from octax_core.env.games import GameSpec, get_spec
from octax_core.env.players import SEATLESS, make_player
from octax_core.validate import check_int
from octax_core.emulator.rom import Rom

POLICIES = SEATLESS  # the table's players that need no seat (octax_core.env.players): "random", "noop"
DEFAULT_STALL_STEPS = 30  # 2 s at 4 frames a step; the suite's longest pause before a serve is 24 (Pong)
RAW_MAX_EPISODE_STEPS = 2**30  # a raw ROM has no episode bound of its own


@dataclasses.dataclass(frozen=True)
class Trace:
    """What `record_trace` saw: T env steps of N envs, episodes restarting when they end.

    Row t holds the state after step t, before any reset, so an episode's last row shows the
    registers the game ended with; the step after it starts a new episode from `reset_regs`.
    """

    game: str  # the game id, or the ROM file name
    regs: np.ndarray  # (T, N, 16) uint8, V0..VF after each step
    pc: np.ndarray  # (T, N) uint16, the program counter after each step
    reward: np.ndarray  # (T, N) float32, the spec's reward (zero when told nothing)
    terminated: np.ndarray  # (T, N) bool, the game ended (spec's rule, or a stall)
    truncated: np.ndarray  # (T, N) bool, the episode bound was reached
    reset_regs: np.ndarray  # (16,) uint8, V0..VF at the start of every episode
    rom: bytes  # the program, for the static half of the ranking
    has_reward: bool = True  # False: the reward is all zeros by construction (blind or raw)
    stall_steps: int = 0  # > 0: episodes ended after this many steps of an unchanged screen

    @property
    def done(self) -> np.ndarray:
        """(T, N) bool: the episode ended at this step (terminated or truncated)."""
        return self.terminated | self.truncated

    @property
    def episode_start(self) -> np.ndarray:
        """(T, N) bool: this step is the first of an episode (it started from `reset_regs`)."""
        start = np.zeros_like(self.done)
        start[0] = True
        start[1:] = self.done[:-1]
        return start

    @property
    def deltas(self) -> np.ndarray:
        """(T, N, 16) int16: each register's change over each step, within episodes."""
        regs = self.regs.astype(np.int16)
        before = np.concatenate([np.broadcast_to(self.reset_regs.astype(np.int16), regs[:1].shape), regs[:-1]])
        before = np.where(self.episode_start[..., None], self.reset_regs.astype(np.int16), before)
        return regs - before


def _zero_score(state):
    return jnp.int32(0)


def _never(state):
    return jnp.bool_(False)


def raw_rom_spec(path: str | Path) -> GameSpec:
    """An ad-hoc `GameSpec` for a ROM file that no registered game describes.

    Actions hold each of the 16 keys (action 0 none), under the "chip8" quirks, with no start-up,
    no reward and no termination: only the register trends and the ROM itself say anything.

    Raises:
        FileNotFoundError: no file at `path`.
        ValueError: the file is empty or too big for a CHIP-8 program.
    """
    rom = Rom.load(path)
    return GameSpec(id=Path(path).name, title=Path(path).name, rom_file=Path(path).name, rom_sha1=rom.sha1,
                    action_keys=tuple(range(16)), score_fn=_zero_score, terminated_fn=_never,
                    category="reaction", description="A raw ROM traced by octax_core.tools.trace.",
                    max_episode_steps=RAW_MAX_EPISODE_STEPS)


def blind_spec(spec: GameSpec) -> GameSpec:
    """`spec` with no reward, lives or termination: its keys, quirks and start-up only."""
    return dataclasses.replace(spec, score_fn=_zero_score, terminated_fn=_never, lives_fn=None)


def record_trace(game: str | GameSpec, *, steps: int, num_envs: int = 8, policy: str = "random",
                 seed: int = 0, blind: bool = False, rom=None,
                 stall_steps: int | None = None) -> Trace:
    """Plays `steps` env steps in `num_envs` envs and records the registers after each step.

    Args:
        game: a registered id or a `GameSpec` (`raw_rom_spec(path)` for a bare ROM).
        steps: env steps per env, >= 1.
        num_envs: envs played side by side, >= 1; each restarts when its episode ends.
        policy: "random" (uniform over the spec's actions) or "noop" (no key ever held): the
            players of `octax_core.env.players`.
        seed: everything random (resets, CXNN, the policy) comes from it: same seed, same trace.
        blind: ignore the spec's reward and termination (what a raw ROM gets).
        rom: an explicit ROM path, as `make` takes it (else the ROM store finds it by SHA-1).
        stall_steps: steps with an unchanged screen that count as a game over; default
            `DEFAULT_STALL_STEPS` when the spec's termination is not used, else off. 0 turns it off.

    Raises:
        KeyError: an unknown game id (the message lists the valid ones).
        ValueError: a bad steps, num_envs, policy or stall_steps.
    """
    spec = game if isinstance(game, GameSpec) else get_spec(game)
    _check_args(steps, num_envs, policy, stall_steps)
    told_nothing = blind or (spec.score_fn is _zero_score and spec.terminated_fn is _never)
    if blind:
        spec = blind_spec(spec)
    if stall_steps is None:
        stall_steps = DEFAULT_STALL_STEPS if told_nothing else 0
    env, params, rom_bytes = _load(spec, None if rom is None else str(rom))
    run = _rollout(env, policy, stall_steps)
    # Env i's keys depend on (seed, i) only, so its rows are the same whatever num_envs is.
    env_keys = jax.vmap(lambda i: jax.random.fold_in(jax.random.key(seed), i))(jnp.arange(num_envs))
    keys = jax.vmap(lambda key: jax.random.split(key, steps + 1))(env_keys)
    start_regs, (regs, pc, reward, terminated, truncated) = jax.device_get(run(keys, params))
    return Trace(game=spec.id, regs=np.swapaxes(regs, 0, 1), pc=np.swapaxes(pc, 0, 1),
                 reward=np.swapaxes(reward, 0, 1), terminated=np.swapaxes(terminated, 0, 1),
                 truncated=np.swapaxes(truncated, 0, 1), reset_regs=start_regs[0],
                 rom=rom_bytes, has_reward=not told_nothing, stall_steps=stall_steps)


def _check_args(steps, num_envs, policy, stall_steps) -> None:
    check_int("steps", steps)
    check_int("num_envs", num_envs)
    if policy not in POLICIES:
        raise ValueError(f"unknown policy {policy!r}; valid: {', '.join(POLICIES)}")
    if stall_steps is not None:
        check_int("stall_steps", stall_steps, minimum=0)


@functools.lru_cache(maxsize=16)
def _load(spec: GameSpec, rom: str | None) -> tuple[Env, EnvParams, bytes]:
    """The env (booted once) and the ROM bytes; cached so that repeated traces reuse one compile."""
    from octax_core.env.romstore import load_game_rom  # file I/O: only when a trace is asked for

    env, params = make(spec, rom=rom)
    return env, params, load_game_rom(spec, rom).data


@functools.lru_cache(maxsize=16)
def _rollout(env: Env, policy: str, stall_steps: int):
    """One jitted program: vmap over envs of a scan over steps, resetting envs whose episode ended."""

    player = make_player(policy, None)
    legal = jnp.ones(env.num_actions, jnp.bool_)

    def play(keys, params):  # keys: (steps + 1,) for one env
        obs, state = env.reset(keys[0], params)

        def step(carry, key):
            obs, state, still = carry
            action_key, step_key, reset_key = jax.random.split(key, 3)
            action = player(None, action_key, obs, state, jnp.int32(0), legal)
            obs, after, reward, terminated, truncated, _ = env.step(step_key, state, action, params)
            still = jnp.where(_unchanged(state.machine, after.machine), still + 1, 0)
            if stall_steps:
                terminated = terminated | (still >= stall_steps)
            ended = terminated | truncated  # the stall rule is the trace's own, so not `after.done`
            obs, state = env.autoreset(reset_key, ended, obs, after, params)
            out = (after.machine.V, after.machine.pc, reward, terminated, truncated & ~terminated)
            return (obs, state, jnp.where(ended, 0, still)), out

        # Every reset gives the same registers (it only reseeds the random state): return them once.
        return state.machine.V, jax.lax.scan(step, (obs, state, jnp.int32(0)), keys[1:])[1]

    return jax.jit(jax.vmap(play, in_axes=(0, None)), compiler_options=env.compiler_options)


def _unchanged(before, after) -> jax.Array:
    """The step left the screen as it was.

    Only the screen counts: a game-over screen often runs a loop whose counters keep changing
    (a blinking message's timer, a key poll), and under a random policy a game in play redraws
    something within 2 s. The cost: under "noop", a game that moves only on a key stalls at once.
    """
    return jnp.all(shown(before) == shown(after))
