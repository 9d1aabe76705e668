"""Collect a Minari dataset of a game with batched lanes, load it back and replay one episode exactly.

    python examples/collect_dataset.py                         # Brix, 2000 random steps, 16 lanes
    python examples/collect_dataset.py --dataset-id octax/Brix-random-v0 --load-only --data-path /tmp/minari

Needs the datasets extra (pip install "octax-gym[datasets]"). Datasets go under --data-path
(default: a temporary folder, removed at the end) as MINARI_DATASETS_PATH. See docs/datasets.md.
"""

import argparse
import os
import shutil
import tempfile

import numpy as np

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--game", default="Brix")
parser.add_argument("--dataset-id", default="octax/Brix-example-v0")
parser.add_argument("--steps", type=int, default=2000)
parser.add_argument("--envs", type=int, default=16)
parser.add_argument("--data-path", default=None, help="MINARI_DATASETS_PATH (default: a temporary folder)")
parser.add_argument("--load-only", action="store_true", help="replay from an existing dataset, collect nothing")
args = parser.parse_args()
os.environ["MINARI_DATASETS_PATH"] = args.data_path or tempfile.mkdtemp(prefix="minari-")  # before minari looks

import minari  # noqa: E402

from octax_gym.datasets import collect_dataset, episode_seed  # noqa: E402

if not args.load_only:
    result = collect_dataset(args.game, args.dataset_id, args.steps, num_envs=args.envs, seed=0, overwrite=True)
    print(f"collected {result.episodes} episodes, {result.steps} steps in {result.seconds:.1f} s "
          f"({result.steps_per_second:,.0f} steps/s) at {result.path}")

dataset = minari.load_dataset(args.dataset_id)
env = dataset.recover_environment()  # gymnasium.make("octax/<Game>-v0", <the collection's options>)

# The last episode the game itself ended (the episodes still running at the stop are stored truncated):
# in a dataset of more episodes than lanes, one started by its lane's reset with a later seed.
episode = next(e for e in (dataset[i] for i in reversed(range(dataset.total_episodes))) if e.terminations[-1])
seed = episode_seed(dataset, episode.id)
obs, _ = env.reset(seed=seed)
same = bool(np.array_equal(obs, episode.observations[0]))
for t, action in enumerate(episode.actions):
    obs, reward, terminated, truncated, _ = env.step(int(action))
    same &= bool(np.array_equal(obs, episode.observations[t + 1]) and reward == episode.rewards[t]
                 and terminated == episode.terminations[t])
print(f"{dataset.id}: {dataset.total_episodes} episodes, {dataset.total_steps} steps; episode {episode.id} "
      f"(seed {seed}, {len(episode)} steps, return {episode.rewards.sum():g}) replayed exactly: {same}")

if args.data_path is None:
    shutil.rmtree(os.environ["MINARI_DATASETS_PATH"])
