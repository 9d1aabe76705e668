"""How far from the device's limit `octax-gym train` runs: env steps/s of the whole update, the
update's floating-point work per env step, and the FLOP/s that makes against the device's peak.

    python benchmarks/train_throughput.py --algo ppo --games Airplane --preset cpu --updates 3
    python benchmarks/train_throughput.py --algo ppo --games octax16 --num-seeds 3 --preset paper   # a GPU

The update is the trainer's own (rollout, targets and the minibatch epochs of every agent, one
jitted program, as `octax_gym.train.loop` compiles it). Its FLOPs are the network's: XLA's count
(`cost_analysis()["flops"]`) of one forward pass and of one gradient (forward and backward) on a
batch of observations, per observation, and per env step one forward (acting) plus
`update_epochs` gradients (each step's sample is in one minibatch per epoch). Not the compiled
update's own count: XLA counts a loop's body once, whatever its trip count, and the update is
loops (the rollout's steps, the epochs, the minibatches). The emulator's integer work and the
loss's few float operations per sample are left out. The peak is measured, not taken from a data sheet: the best FLOP/s of a large float32
matrix product jitted on the same device (on a CPU: all its cores through XLA's thread pool). The
trainer's convolutions are small and memory-bound, so the fraction says how much of the device the
network leaves idle, not how good the code is.

No anchor runs beside it: the octax package ships environments, not a trainer.
Prints free-form lines, then one `BENCH train_throughput key=value ...` line.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402


def matmul_peak(size: int, repeats: int = 5) -> float:
    """The best float32 FLOP/s of a jitted (size x size) @ (size x size) on the default device."""
    import jax
    import jax.numpy as jnp

    a = jax.random.normal(jax.random.key(0), (size, size), jnp.float32)
    b = jax.random.normal(jax.random.key(1), (size, size), jnp.float32)
    product = jax.jit(lambda a, b: a @ b)
    product(a, b).block_until_ready()
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        product(a, b).block_until_ready()
        best = min(best, time.perf_counter() - t0)
    return 2 * size ** 3 / best


def _flops(compiled) -> float:
    cost = compiled.cost_analysis()
    cost = cost[0] if isinstance(cost, (list, tuple)) else cost
    return float(cost["flops"])


def network_flops(network, params, config, batch: int = 256) -> tuple[float, float]:
    """XLA's FLOPs per observation of `network`'s forward pass and of a gradient through it."""
    import jax
    import jax.numpy as jnp

    frames = jnp.zeros((batch, *config_obs_shape(config)), jnp.float32)
    obs = (frames, jnp.zeros(batch, jnp.int32)) if getattr(network, "num_games", 0) else frames

    def outputs(params):
        out = network.apply(params, obs)
        return sum(jnp.sum(x) for x in jax.tree.leaves(out))

    forward = _flops(jax.jit(outputs).lower(params).compile())
    gradient = _flops(jax.jit(jax.grad(outputs)).lower(params).compile())
    return forward / batch, gradient / batch


def config_obs_shape(config) -> tuple:
    """One observation's shape: the frames a step stacks, over the screen (rows, columns)."""
    import octax_core

    env, _ = octax_core.make(config.game_ids[0], **dict(config.env_overrides))
    return tuple(env.observation_shape)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--algo", default="ppo", choices=("ppo", "pqn"))
    parser.add_argument("--games", default="Airplane", help="comma-separated game ids, or octax16")
    parser.add_argument("--num-seeds", type=int, default=1)
    parser.add_argument("--preset", default="cpu", choices=("cpu", "paper"))
    parser.add_argument("--num-envs", type=int, default=None, help="the preset's unless given")
    parser.add_argument("--num-minibatches", type=int, default=None, help="the preset's unless given")
    parser.add_argument("--updates", type=int, default=3, help="timed updates, after one untimed (default 3)")
    parser.add_argument("--matmul-size", type=int, default=2048, help="side of the peak's matrices (default 2048)")
    args = parser.parse_args(argv)
    if args.updates < 1:
        parser.error(f"--updates must be >= 1, got {args.updates}")

    import os
    os.environ.setdefault("OCTAX_ROM_DIR", harness.DEFAULT_ROM_DIR)
    import jax
    import numpy as np

    from octax_gym.train import presets
    from octax_gym.train.algorithm import make_trainer
    from octax_gym.train.config import resolve_games
    from octax_gym.train.envs import Lanes
    from octax_gym.train.many import agent_keys, init_agents, over_agents

    overrides = {k: v for k, v in (("num_envs", args.num_envs), ("num_minibatches", args.num_minibatches))
                 if v is not None}
    config = presets.preset(args.preset, args.algo, games=resolve_games(args.games),
                            num_seeds=args.num_seeds, **overrides)
    lanes = Lanes(config.games, dict(config.env_overrides), config.eval_noop_max, None)
    trainer = make_trainer(config, lanes)
    num_agents = len(config.agent_names)
    games = np.repeat(np.arange(len(config.games)), config.num_seeds)
    runner = init_agents(trainer.init, agent_keys([seed for _, seed in config.agents])[0], games)

    def update(runner):
        runner, batch, metrics = trainer.collect(runner)
        runner, stats = trainer.learn(runner, batch)
        return runner, {**metrics, **stats}

    t0 = time.perf_counter()
    compiled = jax.jit(over_agents(update, num_agents, config.agent_map), donate_argnums=0,
                       compiler_options=lanes.compiler_options).lower(runner).compile()
    compile_s = time.perf_counter() - t0
    steps_per_update = config.batch_size * num_agents
    forward, gradient = network_flops(trainer.network, jax.tree.map(lambda x: x[0], runner.params), config)
    flops = (forward + config.update_epochs * gradient) * steps_per_update

    runner, metrics = compiled(runner)
    jax.block_until_ready(metrics)
    best = float("inf")
    for _ in range(args.updates):
        t0 = time.perf_counter()
        runner, metrics = compiled(runner)
        jax.block_until_ready(metrics)
        best = min(best, time.perf_counter() - t0)
    steps_per_s = steps_per_update / best
    achieved = flops / best
    peak = matmul_peak(args.matmul_size)
    device = jax.devices()[0]
    print(f"{args.algo} on {', '.join(config.game_ids)} x {config.num_seeds} seed(s): {num_agents} agent(s) x "
          f"{config.num_envs} envs x {config.num_steps} steps, {config.update_epochs} epochs x "
          f"{config.num_minibatches} minibatches; compile {compile_s:.1f} s")
    print(f"update: {best:.3f} s, {steps_per_s:,.0f} env steps/s; XLA counts {flops / 1e9:.2f} GFLOP per update, "
          f"{flops / steps_per_update / 1e6:.2f} MFLOP per env step")
    print(f"{achieved / 1e9:.1f} GFLOP/s reached; a {args.matmul_size}^2 float32 matmul reaches {peak / 1e9:.1f} "
          f"GFLOP/s on {device.platform} ({device.device_kind}): {achieved / peak:.1%} of it")
    print(harness.bench_line("train_throughput", {
        "algo": args.algo, "games": len(config.games), "agents": num_agents, "envs": config.num_envs,
        "steps": config.num_steps, "device": device.platform, "compile_s": f"{compile_s:.2f}",
        "update_s": f"{best:.4f}", "sps": f"{steps_per_s:.0f}", "mflop_per_step": f"{flops / steps_per_update / 1e6:.3f}",
        "gflops": f"{achieved / 1e9:.2f}", "peak_gflops": f"{peak / 1e9:.2f}", "fraction": f"{achieved / peak:.4f}"}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
