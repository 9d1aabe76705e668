"""`octax-gym dataset collect` and `dataset suite`: play a game in many lanes at once and write a Minari dataset.

    octax-gym dataset collect Brix --dataset-id octax/Brix-random-v0 --steps 100000 --envs 64
    octax-gym dataset collect Pong --dataset-id octax/Pong-noop-v0 --steps 5000 --policy noop --data-path /tmp/minari
    octax-gym dataset suite --runs runs/suite          # octax/<Game>/{random,medium,expert}-v0
    octax-gym dataset finish octax/Brix-random-v0      # a killed collection's parts as one file

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
    collect.add_argument("--shard", type=int, metavar="R", help="collect shard R of --num-shards P: its share of the "
                         "steps, its own seeds, written as ID with -shardR before the version")
    collect.add_argument("--num-shards", type=int, metavar="P", help="shards in all (with --shard)")
    collect.add_argument("--overwrite", action="store_true", help="replace a dataset of that id")
    collect.add_argument("--no-progress", action="store_true", help="no progress bar")
    collect.set_defaults(func=_cmd_collect)

    combine = sub.add_parser("combine", help="write the episodes of several shards as one dataset",
                             description="Writes the episodes of the shard datasets, in order, with their seeds, "
                                         "into one compact Minari dataset (the shards must come from the same env; "
                                         "no seed in two shards). See docs/datasets.md.")
    combine.add_argument("shards", nargs="+", metavar="SHARD_ID", help="the shard datasets' ids")
    combine.add_argument("--dataset-id", required=True, metavar="ID", help="the combined dataset's id")
    combine.add_argument("--data-path", type=Path, metavar="DIR", help=f"read and write under DIR instead of "
                                                                       f"${DATASETS_PATH_VARIABLE}")
    combine.add_argument("--overwrite", action="store_true", help="replace a dataset of that id")
    combine.set_defaults(func=_cmd_combine)

    finish = sub.add_parser("finish", help="make a killed collection's dataset one file",
                            description="A collection killed part way leaves a readable dataset of the episodes it "
                                        "wrote, its main_data.hdf5 linking to files under data/parts/. This copies "
                                        "them into one self-contained main_data.hdf5, as a finished collection "
                                        "leaves it. Safe to interrupt and run again. See docs/datasets.md.")
    finish.add_argument("dataset", metavar="ID_OR_DIR", help="the dataset's id, or its folder (the one holding data/)")
    finish.add_argument("--data-path", type=Path, metavar="DIR", help=f"look under DIR instead of "
                                                                      f"${DATASETS_PATH_VARIABLE}")
    finish.set_defaults(func=_cmd_finish)

    from octax_gym.datasets import suite  # no JAX or Minari: names and defaults only

    build = sub.add_parser(
        "suite", help="collect the dataset suite (random, medium, expert per game) from trained policies",
        description="Collects octax/<Game>/random-v0, medium-v0 and expert-v0 for the suite's games "
                    f"({', '.join(suite.GAMES)}) from the PPO agents of --runs (octax-gym train ppo --games ... "
                    "--save-at-evals --out-dir RUNS; `make dataset-suite` trains and collects). "
                    "Each dataset's metadata names its policy; the params are copied beside its data. "
                    "Needs the datasets and train extras. See docs/datasets.md.")
    build.add_argument("--runs", type=Path, required=True, metavar="DIR",
                       help="the octax-gym train ppo --save-at-evals run of the games (DIR/agents/Airplane-seed0.msgpack, "
                            "...), or one such run per game (DIR/Airplane/...)")
    build.add_argument("--games", nargs="+", default=list(suite.GAMES), metavar="GAME",
                       help=f"a subset of the suite's games (default: all of {' '.join(suite.GAMES)})")
    build.add_argument("--kinds", nargs="+", default=list(suite.KINDS), metavar="KIND",
                       help="a subset of random medium expert (default: all three)")
    build.add_argument("--steps", type=int, default=suite.STEPS, metavar="N",
                       help=f"steps per dataset (default {suite.STEPS:,})")
    build.add_argument("--envs", type=int, default=suite.ENVS, metavar="K",
                       help=f"lanes (default {suite.ENVS}: long episodes end inside the dataset)")
    build.add_argument("--seed", type=int, default=0, metavar="S", help="the first episode seed and the policies' seed")
    build.add_argument("--data-path", type=Path, metavar="DIR",
                       help=f"write under DIR instead of ${DATASETS_PATH_VARIABLE} (default ~/.minari/datasets)")
    build.add_argument("--overwrite", action="store_true", help="replace datasets of those ids")
    build.add_argument("--no-progress", action="store_true", help="no progress bars")
    build.set_defaults(func=_cmd_suite)


def _cmd_collect(args: argparse.Namespace) -> int:
    from octax_gym.datasets import collect_dataset

    env_options = {} if args.max_episode_steps is None else {"max_episode_steps": args.max_episode_steps}
    dataset_id, steps, seed = args.dataset_id, args.steps, args.seed
    if (args.shard is None) != (args.num_shards is None):
        raise ValueError("--shard R and --num-shards P go together")
    if args.shard is not None:
        from octax_gym.datasets.combine import shard_dataset_id, shard_plan

        steps, seed = shard_plan(args.steps, args.envs, args.seed, args.shard, args.num_shards)
        dataset_id = shard_dataset_id(args.dataset_id, args.shard)
    with _datasets_path(args.data_path):
        result = collect_dataset(args.game, dataset_id, steps, num_envs=args.envs, policy=args.policy,
                                 seed=seed, overwrite=args.overwrite, progress=not args.no_progress,
                                 **env_options)
    print(f"wrote {result.dataset_id}: {result.episodes} episodes, {result.steps} steps in {result.seconds:.1f} s "
          f"({result.steps_per_second:,.0f} steps/s), {_megabytes(result.path):,.1f} MB at {result.path}")
    return 0


def _cmd_combine(args: argparse.Namespace) -> int:
    from octax_gym.datasets.combine import combine_datasets

    with _datasets_path(args.data_path):
        dataset = combine_datasets(args.shards, args.dataset_id, overwrite=args.overwrite)
        path = Path(dataset.storage.data_path).parent
    print(f"wrote {args.dataset_id}: {dataset.total_episodes} episodes, {dataset.total_steps} steps from "
          f"{len(args.shards)} shards, {_megabytes(path):,.1f} MB at {path}")
    return 0


def _cmd_finish(args: argparse.Namespace) -> int:
    from octax_gym.datasets import finish_dataset
    from octax_gym.datasets.damage import load_checked
    from octax_gym.datasets.storage import dataset_folder, import_minari

    import_minari()
    with _datasets_path(args.data_path):
        changed = finish_dataset(args.dataset)  # a damaged folder: a DamagedDatasetError naming the file
        dataset = load_checked(dataset_folder(args.dataset) / "data")
    state = "made one file" if changed else "already one file"
    print(f"{args.dataset}: {state}; {dataset.total_episodes} episodes, {dataset.total_steps} steps")
    return 0


def _cmd_suite(args: argparse.Namespace) -> int:
    from octax_gym.datasets.suite import EVAL_MAX_STEPS, build_suite

    with _datasets_path(args.data_path):
        results = build_suite(args.runs, args.games, args.kinds, steps=args.steps, num_envs=args.envs,
                              seed=args.seed, overwrite=args.overwrite, progress=not args.no_progress)
    for result in results:
        # the episodes the env ended (terminated, or at the cap), not those cut by the end of collection
        whole = [float(e.rewards.sum()) for e in result.dataset.iterate_episodes()
                 if e.terminations[-1] or e.infos["episode_step"][-1] >= EVAL_MAX_STEPS]
        mean = f"{sum(whole) / len(whole):.2f}" if whole else "n/a"
        print(f"wrote {result.dataset_id}: {result.episodes} episodes ({len(whole)} whole: mean return {mean}), "
              f"{result.steps} steps, {_megabytes(result.path):,.1f} MB ({result.steps_per_second:,.0f} steps/s)")
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
