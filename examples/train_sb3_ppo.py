"""Train Stable-Baselines3 PPO with the paper's CNN and hyperparameters on a CHIP-8 game.

    python examples/train_sb3_ppo.py --game Brix --total-steps 200000 --out-dir results/sb3-brix
    python examples/train_sb3_ppo.py --paper                  # the paper's 512 envs (slow on a CPU)

A progress bar runs while training. Every --eval-every env steps (and before the first update)
the current policy plays --eval-episodes episodes on a separate eval env, one episode per env,
always from the same seeds; actions are sampled from the policy unless --deterministic. A uniformly
random policy is measured the same way at the start. Rows go to <out-dir>/progress.csv and the
curve to <out-dir>/learning_curve.png after every evaluation, so an interrupted run keeps both;
the model is saved to <out-dir>/model.zip at the end. Needs `pip install 'octax-gym[sb3,train]'`.
"""

from __future__ import annotations

import argparse
import csv
import json
import time
from pathlib import Path

import numpy as np
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.evaluation import evaluate_policy
from tqdm import tqdm

from octax_gym.sb3 import PAPER_PPO, make_sb3_vec_env, ppo_kwargs

COLUMNS = ("step", "wall_s", "train_s", "env_steps_per_s", "eval_mean_return", "eval_std", "random_mean_return")
EVAL_SEED_OFFSET = 1_000_000  # eval episodes start from seeds that training never uses


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--game", default="Brix")
    parser.add_argument("--num-envs", type=int, default=64, help="training envs (default 64; --paper: 512)")
    parser.add_argument("--paper", action="store_true", help="use the paper's 512 training envs")
    parser.add_argument("--total-steps", type=int, default=200_000, help="env steps to train for")
    parser.add_argument("--eval-every", type=int, default=20_000, help="env steps between evaluations")
    parser.add_argument("--eval-episodes", type=int, default=16, help="episodes per evaluation (one per eval env)")
    parser.add_argument("--deterministic", action="store_true", help="evaluate the greedy action, not a sample")
    parser.add_argument("--time-limit-s", type=float, default=None, help="stop training after this many seconds")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--torch-threads", type=int, default=1,
                        help="torch CPU threads (default 1: with JAX and other work on few cores, "
                             "more threads made each update far slower)")
    parser.add_argument("--out-dir", type=Path, default=Path("results/sb3-brix"))
    args = parser.parse_args(argv)
    if args.paper:
        args.num_envs = PAPER_PPO["num_envs"]
    for name in ("num_envs", "total_steps", "eval_every", "eval_episodes", "torch_threads"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be at least 1")
    return args


class RandomPolicy:
    """Uniformly random actions, with the `predict` signature `evaluate_policy` calls."""

    def __init__(self, num_actions: int, seed: int):
        self.num_actions, self.rng = num_actions, np.random.default_rng(seed)

    def predict(self, obs, state=None, episode_start=None, deterministic=False):
        return self.rng.integers(0, self.num_actions, size=len(obs)), None


class Evaluator:
    """Plays `episodes` episodes, one per env of its own vec env, from the same seeds each time."""

    def __init__(self, game: str, episodes: int, seed: int, deterministic: bool):
        self.venv = make_sb3_vec_env(game, episodes)  # VecMonitor: evaluate_policy reads its episode infos
        self.episodes, self.seed, self.deterministic = episodes, seed + EVAL_SEED_OFFSET, deterministic

    def __call__(self, policy) -> tuple[float, float]:
        self.venv.seed(self.seed)
        mean, std = evaluate_policy(policy, self.venv, n_eval_episodes=self.episodes,
                                    deterministic=self.deterministic)
        return float(mean), float(std)


class TrainLog(BaseCallback):
    """Progress bar, periodic evaluation, CSV rows and the learning-curve PNG; optional time limit."""

    def __init__(self, evaluate: Evaluator, args: argparse.Namespace, random_return: float):
        super().__init__()
        self.evaluate, self.args, self.random_return = evaluate, args, random_return
        self.csv_path, self.png_path = args.out_dir / "progress.csv", args.out_dir / "learning_curve.png"
        self.rows: list[dict] = []
        self.next_eval, self.eval_s, self.start, self.bar = 0, 0.0, 0.0, None

    def _on_training_start(self) -> None:
        with self.csv_path.open("w", newline="") as f:
            csv.writer(f).writerow(COLUMNS)
        self.bar = tqdm(total=self.args.total_steps, unit="step", unit_scale=True, dynamic_ncols=True)
        self.start = time.perf_counter()
        self._evaluate()  # the untrained policy, at step 0

    def _on_step(self) -> bool:
        self.bar.update(self.training_env.num_envs)
        if self.num_timesteps >= self.next_eval:
            self._evaluate()
        limit = self.args.time_limit_s
        return limit is None or time.perf_counter() - self.start < limit

    def _on_training_end(self) -> None:
        if self.rows[-1]["step"] != self.num_timesteps:
            self._evaluate()
        self.bar.close()

    def _evaluate(self) -> None:
        began = time.perf_counter()
        mean, std = self.evaluate(self.model)
        self.eval_s += time.perf_counter() - began
        wall = time.perf_counter() - self.start
        train = wall - self.eval_s
        row = {"step": self.num_timesteps, "wall_s": round(wall, 2), "train_s": round(train, 2),
               "env_steps_per_s": round(self.num_timesteps / train, 1) if self.num_timesteps else 0.0,
               "eval_mean_return": round(mean, 3), "eval_std": round(std, 3),
               "random_mean_return": round(self.random_return, 3)}
        self.rows.append(row)
        with self.csv_path.open("a", newline="") as f:
            csv.writer(f).writerow([row[c] for c in COLUMNS])
        plot(self.rows, self.png_path, self.args)
        self.bar.set_postfix(eval=f"{mean:.1f}", random=f"{self.random_return:.1f}",
                             sps=f"{row['env_steps_per_s']:.0f}")
        self.next_eval = self.num_timesteps + self.args.eval_every


def plot(rows: list[dict], path: Path, args: argparse.Namespace) -> None:
    import matplotlib

    matplotlib.use("Agg")  # files only, no display
    import matplotlib.pyplot as plt

    steps = np.array([r["step"] for r in rows])
    mean = np.array([r["eval_mean_return"] for r in rows])
    std = np.array([r["eval_std"] for r in rows])
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(steps, mean, marker="o", label=f"PPO ({'greedy' if args.deterministic else 'sampled'} actions)")
    ax.fill_between(steps, mean - std, mean + std, alpha=0.2)
    ax.axhline(rows[0]["random_mean_return"], color="gray", linestyle="--", label="random policy")
    ax.set(xlabel="env steps", ylabel=f"mean return over {args.eval_episodes} episodes",
           title=f"SB3 PPO on {args.game}, {args.num_envs} envs")
    ax.legend(loc="best")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> None:
    args = parse_args(argv)
    torch.set_num_threads(args.torch_threads)
    args.out_dir.mkdir(parents=True, exist_ok=True)
    (args.out_dir / "config.json").write_text(json.dumps({**vars(args), "out_dir": str(args.out_dir)}, indent=2))

    venv = make_sb3_vec_env(args.game, args.num_envs)
    evaluate = Evaluator(args.game, args.eval_episodes, args.seed, args.deterministic)
    random_return, _ = evaluate(RandomPolicy(venv.action_space.n, args.seed))
    print(f"{args.game}: random policy mean return {random_return:.2f} over {args.eval_episodes} episodes")

    model = PPO("CnnPolicy", venv, seed=args.seed, **ppo_kwargs(args.num_envs))
    log = TrainLog(evaluate, args, random_return)
    model.learn(args.total_steps, callback=log)
    model.save(args.out_dir / "model.zip")

    last = log.rows[-1]
    print(f"{args.game}: {last['step']} env steps, {last['env_steps_per_s']:.0f} env steps/s of training "
          f"(evaluations excluded), eval mean return {last['eval_mean_return']:.2f} "
          f"(random {random_return:.2f}); wrote {log.csv_path} and {log.png_path}")


if __name__ == "__main__":
    main()
