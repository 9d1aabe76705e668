"""Many games in one batch: a mix's env steps/s against the same games run one program each.

N envs of a mix (`octax_core.make_mix`), env i playing game i mod G, step `--steps` times in one
jitted `lax.scan` of the vmapped `env.step` (autoreset on, each env's action uniform over its own
game's actions, drawn inside the scan); then each game alone (`octax_core.make`) on the same
work at the same N. All sides are timed alternately in one process, best of `--repeats`, compile
time excluded. The target of issue 23: the mix at >= 0.7x the mean of the single games' steps/s.

Prints one ``BENCH mix_game`` line per game and one ``BENCH mix`` line: `mix_sps`,
`single_mean_sps`, `ratio`, and the compile times (`mix_compile_s` against the sum of the single
games' `single_compile_s`). The octax package has one jitted env per ROM and no mix; its
counterpart of the mix is the single-game programs measured here.

    python benchmarks/mix.py                        # the octax16 mix (docs/mix.md), N = 512
    python benchmarks/mix.py --games Pong,Brix,Tetris --envs 64
"""

from __future__ import annotations

import argparse
import sys
from typing import Optional

from harness import BenchError, Prepared, Progress, bench_line, compile_rollout, load_average, state_bytes, time_interleaved


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--games", default="octax16", help="a named mix (octax16) or comma-separated game ids")
    parser.add_argument("--envs", type=int, default=512, help="batch size N (default 512)")
    parser.add_argument("--steps", type=int, default=50, help="env steps per timed run (default 50)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per side, the best counts (default 3)")
    args = parser.parse_args(argv)
    from octax_core.env.mix import MIXES

    games = list(MIXES[args.games]) if args.games in MIXES else [g.strip() for g in args.games.split(",")]
    if args.envs < len(games) or args.steps < 1 or args.repeats < 1:
        parser.error(f"--envs must be >= the number of games ({len(games)}); --steps and --repeats >= 1")
    try:
        return run(games, args)
    except (BenchError, KeyError, ValueError) as exc:
        print(f"{parser.prog}: error: {exc}", file=sys.stderr)
        return 1


def prepare(env, params, n: int, steps: int, games=None) -> Prepared:
    """`steps` autoreset steps of n envs; with `games`, env i plays game games[i]."""
    import jax
    import jax.numpy as jnp

    keys = jax.random.split(jax.random.key(0), n)
    if games is None:
        states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)[1]
        counts = jnp.full((n,), env.num_actions)
    else:
        states = jax.vmap(lambda k, g: env.reset(k, params, game=g))(keys, games)[1]
        counts = jnp.asarray([len(spec.action_keys) + 1 for spec in env.specs])

    def rollout(states, keys):
        def one(carry, _):
            states, keys = carry
            split = jax.vmap(lambda k: jax.random.split(k, 3))(keys)
            own = counts if games is None else counts[states.game]  # after autoreset, a new game
            actions = jax.vmap(lambda k, c: jax.random.randint(k, (), 0, c))(split[:, 1], own)
            out = jax.vmap(env.step, in_axes=(0, 0, 0, None))(split[:, 2], states, actions, params)
            return (out[1], split[:, 0]), out[2].sum()

        (states, keys), rewards = jax.lax.scan(one, (states, keys), length=steps)
        return states, rewards

    run, compile_s, _ = compile_rollout(rollout, states, keys, compiler_options=env.compiler_options)
    return Prepared(run, compile_s, state_bytes(states), 0)


def run(games: list[str], args: argparse.Namespace) -> int:
    import jax
    import jax.numpy as jnp

    import octax_core

    n = args.envs
    print(f"# jax {jax.__version__} backend={jax.default_backend()} devices={jax.device_count()} "
          f"games={len(games)} n={n}", flush=True)
    mix, params = octax_core.make_mix(games, autoreset=True)
    sides = {"mix": prepare(mix, params, n, args.steps, jnp.arange(n) % len(games))}
    for game in games:
        env, env_params = octax_core.make(game, autoreset=True)
        sides[game] = prepare(env, env_params, n, args.steps)
    time_interleaved(sides, args.repeats, Progress(0, False), f"n={n}")
    sps = {name: n * args.steps / side.best_s for name, side in sides.items()}
    for game in games:
        print(bench_line("mix_game", {"game": game, "n": n, "sps": round(sps[game]),
                                      "compile_s": round(sides[game].compile_s, 2)}), flush=True)
    mean = sum(sps[g] for g in games) / len(games)
    single_compile = sum(sides[g].compile_s for g in games)
    print(f"mix of {len(games)} games n={n}: {sps['mix']:,.0f} steps/s; the games alone: mean {mean:,.0f} "
          f"({sps['mix'] / mean:.2f}x); compile {sides['mix'].compile_s:.1f} s against {single_compile:.1f} s "
          f"for the {len(games)} alone; load {load_average():.2f}", flush=True)
    print(bench_line("mix", {
        "games": len(games), "n": n, "steps": args.steps, "mix_sps": round(sps["mix"]),
        "single_mean_sps": round(mean), "ratio": round(sps["mix"] / mean, 3),
        "mix_compile_s": round(sides["mix"].compile_s, 2), "single_compile_s": round(single_compile, 2),
        "state_bytes": sides["mix"].state_bytes, "device": jax.default_backend(),
    }), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
