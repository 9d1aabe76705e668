"""PPO with TorchRL on an octax game: the native batched env, a Collector, GAE and ClipPPOLoss.

    python examples/train_torchrl_ppo.py --game Brix --max-minutes 2         # 64 envs, for a 2-core CPU
    python examples/train_torchrl_ppo.py --game Brix --paper --device cuda   # the paper's 512 envs

The agent is the Octax paper's (`octax_gym.networks.ActorCritic`: a CNN torso with separate actor and
critic heads), trained with the paper's PPO hyperparameters (the defaults below; only the number of
envs is smaller unless --paper). Every --eval-every env steps the current policy plays
--eval-episodes episodes (one per env, sampling its actions as the paper's evaluation does) on a
separate env; a uniform random policy is measured once at the start as the baseline.

Writes to --out (default runs/torchrl-ppo-<game>): progress.csv (step, wall_s, env_steps_per_s,
eval_mean_return, eval_std, random_mean_return; env_steps_per_s counts training steps over training
time, evaluations excluded) and learning_curve.png, both rewritten after each evaluation.
"""

from __future__ import annotations

import argparse
import csv
import os
import time
from pathlib import Path

os.environ.setdefault("OCTAX_ROM_DIR", str(Path(__file__).resolve().parents[1] / "../shared/roms/octax"))

import matplotlib

matplotlib.use("Agg")  # files only, no window
import matplotlib.pyplot as plt
import torch
from tensordict.nn import TensorDictModule
from torchrl.collectors import Collector
from torchrl.envs.utils import ExplorationType, set_exploration_type
from torchrl.modules import ActorValueOperator, ProbabilisticActor
from torchrl.objectives import ClipPPOLoss
from torchrl.objectives.value import GAE
from tqdm import tqdm

from octax_gym.networks import ActorCritic
from octax_gym.torchrl import make_torchrl_env

CSV_COLUMNS = ("step", "wall_s", "env_steps_per_s", "eval_mean_return", "eval_std", "random_mean_return")
PAPER_NUM_ENVS = 512


def parse_args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--game", default="Brix")
    p.add_argument("--num-envs", type=int, default=64)
    p.add_argument("--paper", action="store_true", help=f"the paper's {PAPER_NUM_ENVS} envs")
    p.add_argument("--num-steps", type=int, default=32, help="rollout length per env")
    p.add_argument("--epochs", type=int, default=4)
    p.add_argument("--minibatches", type=int, default=32)
    p.add_argument("--lr", type=float, default=5e-4)
    p.add_argument("--gamma", type=float, default=0.99)
    p.add_argument("--gae-lambda", type=float, default=0.95)
    p.add_argument("--clip", type=float, default=0.2)
    p.add_argument("--vf-coef", type=float, default=0.5)
    p.add_argument("--ent-coef", type=float, default=0.01)
    p.add_argument("--max-grad-norm", type=float, default=0.5)
    p.add_argument("--total-steps", type=int, default=5_000_000,
                   help="env steps (the paper's budget), rounded up to whole batches")
    p.add_argument("--max-minutes", type=float, default=None, help="stop training after this wall time")
    p.add_argument("--eval-every", type=int, default=131_072, help="env steps (the paper's eval_freq)")
    p.add_argument("--eval-episodes", type=int, default=32)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--device", default="cpu")
    p.add_argument("--torch-threads", type=int, default=1,
                   help="torch CPU threads; on 2 cores one left to the JAX env trained fastest")
    p.add_argument("--out", type=Path, default=None)
    args = p.parse_args(argv)
    if args.paper:
        args.num_envs = PAPER_NUM_ENVS
    args.out = args.out or Path("runs") / f"torchrl-ppo-{args.game.lower()}"
    batch = args.num_envs * args.num_steps
    if batch % args.minibatches:
        p.error(f"--minibatches {args.minibatches} must divide num_envs * num_steps = {batch}")
    args.total_steps = -(-args.total_steps // batch) * batch
    return args


def build_agent(env, device) -> ActorValueOperator:
    """The paper's network as TorchRL modules: a shared torso, a Categorical policy and a value head."""
    net = ActorCritic(env.action_spec.n, frames=env.observation_spec["observation"].shape[-3]).to(device)
    torso = TensorDictModule(net.torso, in_keys=["observation"], out_keys=["features"])
    policy = ProbabilisticActor(TensorDictModule(net.actor, in_keys=["features"], out_keys=["logits"]),
                                in_keys=["logits"], distribution_class=torch.distributions.Categorical,
                                return_log_prob=True, spec=env.action_spec)
    value = TensorDictModule(net.critic, in_keys=["features"], out_keys=["state_value"])
    return ActorValueOperator(torso, policy, value)


@torch.no_grad()
def play_episodes(env, act, seed: int) -> torch.Tensor:
    """The return of one episode per env. The env does not autoreset: an ended env stands still
    with reward 0 until every episode has ended (at the latest, at max_episode_steps)."""
    env.set_seed(seed)
    td = env.reset()
    returns = torch.zeros(env.num_envs, device=env.device)
    while not td["done"].all():
        td = env.step(act(td))["next"]
        returns += td["reward"].squeeze(-1)
    return returns.cpu()


def ppo_update(data, loss_module, advantage, optimizer, args) -> dict[str, float]:
    """The paper's update: GAE once over the batch, then epochs of shuffled minibatches."""
    with torch.no_grad():
        advantage(data)  # writes "advantage" and "value_target"; data is (num_envs, num_steps)
    flat = data.reshape(-1)
    size = flat.numel() // args.minibatches
    params = list(loss_module.parameters())
    for _ in range(args.epochs):
        for index in torch.randperm(flat.numel(), device=flat.device).split(size):
            losses = loss_module(flat[index])
            loss = losses["loss_objective"] + losses["loss_critic"] + losses["loss_entropy"]
            optimizer.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(params, args.max_grad_norm)
            optimizer.step()
    return {k: float(v.detach()) for k, v in losses.items() if k.startswith("loss_")}


def make_loss(agent: ActorValueOperator, args) -> tuple[ClipPPOLoss, GAE]:
    value = agent.get_value_operator()
    advantage = GAE(gamma=args.gamma, lmbda=args.gae_lambda, value_network=value, average_gae=False)
    # The paper's value loss is 0.5 * vf_coef * (v - target)^2 with the value clipped like the
    # ratio, and advantages normalised per minibatch (rejax's PPO); TorchRL's "l2" has no 0.5.
    loss = ClipPPOLoss(agent.get_policy_operator(), value, clip_epsilon=args.clip, entropy_coeff=args.ent_coef,
                       critic_coeff=0.5 * args.vf_coef, loss_critic_type="l2", normalize_advantage=True,
                       clip_value=True)
    return loss, advantage


class Log:
    """Evaluations, timed apart from training, into progress.csv and learning_curve.png."""

    def __init__(self, out: Path, game: str, eval_env, policy, seed: int):
        out.mkdir(parents=True, exist_ok=True)
        self.out, self.game, self.eval_env, self.policy, self.seed = out, game, eval_env, policy, seed
        def random_policy(td):
            return td.set("action", eval_env.action_spec.rand())

        self.random_mean = float(play_episodes(eval_env, random_policy, seed).mean())
        self.rows, self.start, self.eval_s = [], time.perf_counter(), 0.0

    def wall(self) -> float:
        return time.perf_counter() - self.start

    def steps_per_s(self, steps: int) -> float:
        """Training env steps per second of training time (evaluations excluded)."""
        return steps / max(self.wall() - self.eval_s, 1e-9)

    def evaluate(self, steps: int) -> dict:
        """The current policy's returns, sampling its actions (as the paper's evaluation does)."""
        t = time.perf_counter()
        with set_exploration_type(ExplorationType.RANDOM):
            returns = play_episodes(self.eval_env, self.policy, self.seed + 1 + steps)
        self.eval_s += time.perf_counter() - t
        row = {"step": steps, "wall_s": round(self.wall(), 2), "env_steps_per_s": round(self.steps_per_s(steps), 1),
               "eval_mean_return": round(float(returns.mean()), 3), "eval_std": round(float(returns.std()), 3),
               "random_mean_return": round(self.random_mean, 3)}
        self.rows.append(row)
        with open(self.out / "progress.csv", "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=CSV_COLUMNS)
            writer.writeheader()
            writer.writerows(self.rows)
        self._plot()
        return row

    def _plot(self):
        steps = [r["step"] for r in self.rows]
        mean = torch.tensor([r["eval_mean_return"] for r in self.rows])
        std = torch.tensor([r["eval_std"] for r in self.rows])
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.plot(steps, mean, marker="o", label="PPO (TorchRL), eval mean")
        ax.fill_between(steps, mean - std, mean + std, alpha=0.2)
        ax.axhline(self.random_mean, color="gray", linestyle="--", label="random policy")
        ax.set(xlabel="env steps", ylabel="episode return", title=f"{self.game}: PPO with TorchRL")
        ax.legend()
        fig.tight_layout()
        fig.savefig(self.out / "learning_curve.png", dpi=120)
        plt.close(fig)


def main(argv=None):
    args = parse_args(argv)
    torch.manual_seed(args.seed)
    torch.set_num_threads(args.torch_threads)
    env = make_torchrl_env(args.game, args.num_envs, device=args.device)
    agent = build_agent(env, env.device)
    policy = agent.get_policy_operator()
    loss_module, advantage = make_loss(agent, args)
    optimizer = torch.optim.Adam(loss_module.parameters(), lr=args.lr)
    eval_env = make_torchrl_env(args.game, args.eval_episodes, device=args.device)
    log = Log(args.out, args.game, eval_env, policy, seed=args.seed + 1_000_000)
    print(f"{args.game}: {args.num_envs} envs x {args.num_steps} steps per batch; "
          f"random policy {log.random_mean:.2f} over {args.eval_episodes} episodes")

    env.set_seed(args.seed)
    # The policy is feed-forward: it needs no InitTracker, which TorchRL 0.14 would warn about.
    collector = Collector(env, policy, frames_per_batch=args.num_envs * args.num_steps,
                          total_frames=args.total_steps, device=env.device, auto_register_policy_transforms=False)
    steps, next_eval = 0, 0
    bar = tqdm(total=args.total_steps, unit="step", dynamic_ncols=True)
    for data in collector:
        if steps >= next_eval:  # the policy that collected this batch, before it learns from it
            row = log.evaluate(steps)
            bar.write(f"step {steps}: eval return {row['eval_mean_return']:.2f} +- {row['eval_std']:.2f}")
            next_eval += args.eval_every
        losses = ppo_update(data, loss_module, advantage, optimizer, args)
        steps += data.numel()
        bar.update(data.numel())
        bar.set_postfix(sps=f"{log.steps_per_s(steps):.0f}", loss=f"{sum(losses.values()):.3f}")
        if args.max_minutes is not None and log.wall() > 60 * args.max_minutes:
            break
    bar.close()
    collector.shutdown()
    row = log.evaluate(steps)
    print(f"final: {steps} env steps in {row['wall_s']:.0f} s ({row['env_steps_per_s']:.0f} training steps/s); "
          f"eval return {row['eval_mean_return']:.2f} +- {row['eval_std']:.2f} "
          f"(random {log.random_mean:.2f}); wrote {args.out}/progress.csv and learning_curve.png")


if __name__ == "__main__":
    main()
