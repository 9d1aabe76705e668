"""What the second player costs: a two-player game's multi-agent env against its one-player env.

For each game, N envs step `--steps` times in one jitted `lax.scan` of the vmapped `env.step`
(autoreset on, uniform random actions drawn inside the scan from each env's own key), best of
`--repeats` timed runs, compile time excluded, the two sides timed alternately in one process:

    one       `octax_core.make(game)`: one agent, one action a step (player 2 holds no key)
    two       `octax_core.make_multi(game)`: one action per seat, both seats' keys on the one
              keypad, per-seat rewards, the (players, frames + 1, H, W) observation

Each (game, N) prints one ``BENCH two_player`` line: `one_sps` and `two_sps` (env steps/s, a
two-player step moving both players) and `ratio` = two_sps / one_sps. A game that is not a
one-player env (`GameSpec.solo` False: a turn-based game that waits for its second player) has
`one_sps=na`. The octax package has no two-player envs, so there is no octax side here.

    python benchmarks/two_player.py                       # every two-player game, N = 512
    python benchmarks/two_player.py --games SpaceRacer,Duel --envs 64,512
"""

from __future__ import annotations

import argparse
import sys
from typing import Optional

from harness import BenchError, Prepared, Progress, bench_line, compile_rollout, load_average, state_bytes, time_interleaved


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--games", default="all", help="comma-separated two-player game ids, or all (default)")
    parser.add_argument("--envs", default="512", help="comma-separated batch sizes N (default 512)")
    parser.add_argument("--steps", type=int, default=100, help="env steps per timed run (default 100)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per side, the best counts (default 3)")
    args = parser.parse_args(argv)
    import octax_core

    two_player = octax_core.list_games(players=2)
    games = two_player if args.games == "all" else [g.strip() for g in args.games.split(",")]
    try:
        envs = [int(n) for n in args.envs.split(",")]
    except ValueError:
        parser.error(f"--envs must be comma-separated positive integers, got {args.envs!r}")
    if min(envs) < 1 or args.steps < 1 or args.repeats < 1:
        parser.error("--envs, --steps and --repeats must be >= 1")
    if unknown := [g for g in games if g not in two_player]:
        parser.error(f"not two-player game(s): {unknown}; valid: {', '.join(two_player)}")
    try:
        return run(games, envs, args)
    except BenchError as exc:
        print(f"{parser.prog}: error: {exc}", file=sys.stderr)
        return 1


def prepare(env, params, n: int, steps: int, seats: Optional[int]) -> Prepared:
    """`steps` autoreset steps of n envs, random actions: one per env (seats None) or per seat."""
    import jax

    keys = jax.random.split(jax.random.key(0), n)
    states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)[1]
    shape = () if seats is None else (seats,)

    def rollout(states, keys):
        def one(carry, _):
            states, keys = carry
            split = jax.vmap(lambda k: jax.random.split(k, 3))(keys)
            actions = jax.vmap(lambda k: jax.random.randint(k, shape, 0, env.num_actions))(split[:, 1])
            out = jax.vmap(env.step, in_axes=(0, 0, 0, None))(split[:, 2], states, actions, params)
            return (out[1], split[:, 0]), out[2].sum()  # the rewards, so nothing is dead code

        (states, keys), rewards = jax.lax.scan(one, (states, keys), length=steps)
        return states, rewards

    run, compile_s, _ = compile_rollout(rollout, states, keys, compiler_options=env.compiler_options)
    return Prepared(run, compile_s, state_bytes(states), env.config.frames_per_step * env.config.instructions_per_frame)


def run(games: list[str], envs: list[int], args: argparse.Namespace) -> int:
    import jax

    import octax_core

    print(f"# jax {jax.__version__} backend={jax.default_backend()} devices={jax.device_count()}", flush=True)
    progress = Progress(0, False)
    for game in games:
        spec = octax_core.get_spec(game)
        for n in envs:
            sides = {}
            if spec.solo:
                env, params = octax_core.make(game, autoreset=True)
                sides["one"] = prepare(env, params, n, args.steps, None)
            multi, params = octax_core.make_multi(game, autoreset=True)
            sides["two"] = prepare(multi, params, n, args.steps, multi.players)
            time_interleaved(sides, args.repeats, progress, f"{game} n={n}")
            sps = {name: n * args.steps / side.best_s for name, side in sides.items()}
            one = sps.get("one")
            ratio = sps["two"] / one if one else None
            print(f"{game} n={n}: two players {sps['two']:,.0f} steps/s"
                  + (f", one player {one:,.0f} ({ratio:.2f}x)" if one else " (not a one-player game)")
                  + f", compile {sides['two'].compile_s:.2f} s, load {load_average():.2f}", flush=True)
            print(bench_line("two_player", {
                "game": game, "n": n, "steps": args.steps, "platform": spec.platform,
                "one_sps": round(one) if one else None, "two_sps": round(sps["two"]),
                "ratio": round(ratio, 3) if ratio else None, "state_bytes": sides["two"].state_bytes,
                "compile_s": round(sides["two"].compile_s, 2), "device": jax.default_backend(),
            }), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
