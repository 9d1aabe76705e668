"""`octax-gym dataset collect`: play a game in many lanes at once and write a Minari dataset.

    octax-gym dataset collect Brix --dataset-id octax/Brix-random-v0 --steps 100000 --envs 64
    octax-gym dataset collect Pong --dataset-id octax/Pong-noop-v0 --steps 5000 --policy noop --data-path /tmp/minari

A thin layer over `octax_gym.datasets.collect_dataset`, which checks the arguments (its errors
name the valid choices) and is imported only when the command runs: it brings JAX and Minari.
"""

from __future__ import annotations

import argparse
import contextlib
import os
from pathlib import Path
from typing import Iterator, Optional

from octax_gym.cli.common import help_of

DATASETS_PATH_VARIABLE = "MINARI_DATASETS_PATH"  # where Minari reads and writes datasets


def add_commands(commands: argparse._SubParsersAction) -> None:
    """Adds `dataset` and its actions to the `octax-gym` parser."""
    dataset = commands.add_parser("dataset", help="collect offline datasets (Minari)",
                                  description="Offline datasets in Minari's format; see docs/datasets.md.")
    dataset.set_defaults(func=help_of(dataset))
    sub = dataset.add_subparsers(title="dataset commands", metavar="ACTION")
    collect = sub.add_parser(
        "collect", help="play N steps in K lanes at once and write every episode as a Minari dataset",
        description="Steps K lanes of a game in one jitted call and writes every episode (exact uint8 "
                    "observations, actions, rewards, flags, score and lives, and a seed that replays "
                    "it) as a Minari HDF5 dataset that minari.load_dataset(ID) loads. Needs the "
                    "datasets extra: pip install 'octax-gym[datasets]'. See docs/datasets.md.")
    collect.add_argument("game", metavar="GAME", help="game id (Brix) or Gymnasium id (octax/Brix-v0); "
                                                      "`octax-gym list` shows the games")
    collect.add_argument("--dataset-id", required=True, metavar="ID",
                         help="Minari id namespace/name-vN, e.g. octax/Brix-random-v0 (namespace optional; "
                              "letters, digits, '-', '_'; the version is required)")
    collect.add_argument("--steps", type=int, required=True, metavar="N", help="transitions to store in all")
    collect.add_argument("--envs", type=int, default=64, metavar="K", help="lanes stepped together (default 64)")
    collect.add_argument("--seed", type=int, default=0, metavar="S",
                         help="the first episode seed (episodes get S, S+1, ...) and the random policy's seed")
    collect.add_argument("--policy", default="random", metavar="random|noop",
                         help="random (default: uniform actions) or noop (action 0: no key held)")
    collect.add_argument("--max-episode-steps", type=int, metavar="M",
                         help="truncate episodes after M steps (default: the game's own)")
    collect.add_argument("--data-path", type=Path, metavar="DIR",
                         help=f"write under DIR instead of ${DATASETS_PATH_VARIABLE} (default ~/.minari/datasets); "
                              f"load it with {DATASETS_PATH_VARIABLE}=DIR")
    collect.add_argument("--overwrite", action="store_true", help="replace a dataset of that id")
    collect.add_argument("--no-progress", action="store_true", help="no progress bar")
    collect.set_defaults(func=_cmd_collect)


def _cmd_collect(args: argparse.Namespace) -> int:
    from octax_gym.datasets import collect_dataset

    env_options = {} if args.max_episode_steps is None else {"max_episode_steps": args.max_episode_steps}
    with _datasets_path(args.data_path):
        result = collect_dataset(args.game, args.dataset_id, args.steps, num_envs=args.envs, policy=args.policy,
                                 seed=args.seed, overwrite=args.overwrite, progress=not args.no_progress,
                                 **env_options)
    print(f"wrote {result.dataset_id}: {result.episodes} episodes, {result.steps} steps in {result.seconds:.1f} s "
          f"({result.steps_per_second:,.0f} steps/s), {_megabytes(result.path):,.1f} MB at {result.path}")
    return 0


@contextlib.contextmanager
def _datasets_path(path: Optional[Path]) -> Iterator[None]:
    """Points Minari at `path` for the duration (Minari takes its folder from the environment only)."""
    if path is None:
        yield
        return
    before = os.environ.get(DATASETS_PATH_VARIABLE)
    os.environ[DATASETS_PATH_VARIABLE] = str(path.expanduser().resolve())
    try:
        yield
    finally:
        if before is None:
            del os.environ[DATASETS_PATH_VARIABLE]
        else:
            os.environ[DATASETS_PATH_VARIABLE] = before


def _megabytes(folder: Path) -> float:
    return sum(file.stat().st_size for file in folder.rglob("*") if file.is_file()) / 1e6
