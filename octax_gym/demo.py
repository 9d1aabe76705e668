"""`python -m octax_gym.demo` (`make demo`): the games, a random agent's speed on Pong, and a video.

    python -m octax_gym.demo [--steps 2000] [--envs 64] [--video-steps 300] [--out demo-pong.mp4]

1. The games table: Gymnasium id, category, number of actions, and whether the ROM is present.
2. A random agent plays Pong in `--envs` envs through `gymnasium.make_vec` for `--steps` steps.
   Steps per second leave out the reset and the first step, which compile the program (seconds,
   once per process), so the figure is the steady speed a training loop would see. It does include
   the host side of each step: drawing the random actions and handing numpy arrays back.
3. `octax_gym.video.record` plays `--video-steps` more steps in a grid of up to 4 envs and writes
   an mp4 (a fresh run: rendering 64 screens a step would slow the timed run down).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from typing import Optional, Sequence

import gymnasium
import numpy as np
from tqdm import tqdm

import octax_gym
from octax_core.env import romstore
from octax_gym import video
from octax_gym.cli.common import game_specs, print_table

GAME = "Pong"
VIDEO_ENVS = 4  # a 2 x 2 grid: large enough to show that the games differ, small enough to watch


@dataclasses.dataclass(frozen=True)
class AgentRun:
    """A timed random-agent run: `env_steps` counts env steps after the first (compiling) step."""

    num_envs: int
    env_steps: int
    seconds: float
    compile_seconds: float
    frames_per_step: int
    returns: tuple[float, ...]  # one per episode that ended

    @property
    def steps_per_second(self) -> float:
        return self.env_steps / self.seconds


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Runs the demo; returns the exit status (0 ok, 1 failed: e.g. the Pong ROM is missing)."""
    args = _parse(argv)
    print_games()
    try:
        run = run_random_agent(GAME, args.envs, args.steps, args.seed)
        print_run(run)
        print()
        result = video.record(GAME, args.out, steps=args.video_steps, num_envs=min(VIDEO_ENVS, args.envs),
                              seed=args.seed)
    except (romstore.RomNotFoundError, romstore.RomHashError, ImportError, OSError, ValueError) as exc:
        print(f"octax_gym.demo: error: {exc}", file=sys.stderr)
        return 1
    print(f"video: {result.path.resolve()}\n       {result.frames} frames, {result.width}x{result.height} "
          f"at {result.fps:g} fps ({result.seconds:.1f} s), {result.episodes} episode(s) ended")
    return 0


def _parse(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="python -m octax_gym.demo", description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=_at_least(2), default=2000,
                        help="steps of the timed run (default 2000; a random Pong episode lasts about 1000)")
    parser.add_argument("--envs", type=_at_least(1), default=64, help="envs in the timed run (default 64)")
    parser.add_argument("--video-steps", type=_at_least(1), default=300,
                        help="steps in the video (default 300: 20 s at 15 fps)")
    parser.add_argument("--out", default="demo-pong.mp4", help="the video file (default demo-pong.mp4)")
    parser.add_argument("--seed", type=int, default=0, help="seeds the envs and the random agent")
    return parser.parse_args(argv)


def _at_least(minimum: int):
    def parse(text: str) -> int:
        value = int(text)
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {value}")
        return value
    parse.__name__ = "int"  # argparse names the type in its "invalid int value" message
    return parse


def print_games() -> None:
    """The games table: Gymnasium id, category, actions (no-op included), ROM present/verified."""
    specs = game_specs()
    roms = {row.game_id: row for row in romstore.rom_status(specs)}
    rows = [("env id", "category", "actions", "ROM")]
    for spec in specs:
        status = roms[spec.id]
        rom = "yes" if status.verified else ("missing" if status.path is None else "wrong SHA-1")
        rows.append((octax_gym.env_id(spec.id), spec.category, str(len(spec.action_keys) + 1), rom))
    print_table(rows)
    ready = sum(row.verified for row in roms.values())
    print(f"\n{len(specs)} envs, {ready} with their ROM." + ("" if ready == len(specs) else
          f" To get the missing ones: {romstore.FIX_HINT}."))
    print()


def run_random_agent(game: str, num_envs: int, steps: int, seed: int) -> AgentRun:
    """Plays `steps` steps of uniformly random actions in `num_envs` envs; times all but the first."""
    envs = gymnasium.make_vec(octax_gym.env_id(game), num_envs=num_envs)
    try:
        envs.action_space.seed(seed)
        episode_return, returns = np.zeros(num_envs), []
        start = time.perf_counter()
        envs.reset(seed=seed)
        for index in tqdm(range(steps), desc=f"random agent, {num_envs} x {game}", unit="step"):
            _, reward, terminated, truncated, _ = envs.step(envs.action_space.sample())
            episode_return += reward
            ended = np.asarray(terminated | truncated)
            returns.extend(episode_return[ended].tolist())
            episode_return[ended] = 0.0
            if index == 0:  # reset and the first step compiled the program: time from here on
                compile_seconds, start = time.perf_counter() - start, time.perf_counter()
        seconds = time.perf_counter() - start
        frames_per_step = envs.unwrapped.core_env.config.frames_per_step
    finally:
        envs.close()
    return AgentRun(num_envs=num_envs, env_steps=num_envs * (steps - 1), seconds=seconds,
                    compile_seconds=compile_seconds, frames_per_step=frames_per_step, returns=tuple(returns))


def print_run(run: AgentRun) -> None:
    print(f"compile (reset + first step): {run.compile_seconds:.1f} s, not counted below")
    print(f"{run.env_steps:,} env steps in {run.seconds:.2f} s: {run.steps_per_second:,.0f} steps/s "
          f"({run.steps_per_second * run.frames_per_step:,.0f} CHIP-8 frames/s, {run.frames_per_step} a step)")
    if run.returns:
        print(f"{len(run.returns)} episodes ended; mean return {np.mean(run.returns):+.2f} "
              f"(min {min(run.returns):+g}, max {max(run.returns):+g}; a point won is +1, one lost -1)")
    else:
        print("no episode ended yet (a random Pong episode lasts about 1000 steps; try --steps 2000)")


if __name__ == "__main__":
    sys.exit(main())
