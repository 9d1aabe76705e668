"""skip_idle on every registered game: env steps/s with it off and on, and proof they agree.

For each game and batch size N, two envs are made, `octax_core.make(game, autoreset=True,
skip_idle=False)` and the same with `skip_idle=True`, and each runs the same jitted rollout from
the same start (N envs reset from one key, untimed): `--steps` steps of `jax.vmap(env.step)` in a
`lax.scan`, with uniform random actions drawn once (seeded) and shared by both sides, the latest
observation carried along. A timed run is one whole rollout (best of `--repeats`, the sides
alternating; compile excluded); it returns every step's reward, flags and score and the final
observation and env state. An untimed run of each side also returns a fingerprint of every step's
observation (a position-weighted uint32 sum: on a 64x128 game it costs more than a few
instructions' step, so it is not timed). `exact` says whether all of these are equal.

    python benchmarks/skip_idle.py                                    # every game, N = 64
    python benchmarks/skip_idle.py --games archive200 --envs 64,512   # the archive's >= 200 ipf games
    python benchmarks/skip_idle.py --markdown docs/speed.md           # also write the table page

One `BENCH skip_idle ...` line per (game, N), then one `BENCH skip_idle_summary ...` line per
(group, N) with the geometric-mean speed-up, for the archive games at >= 200 instructions per
frame and for all games measured.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import os
import platform
import sys
import time
from pathlib import Path
from typing import Optional

from harness import Prepared, Progress, bench_line, load_average, time_interleaved

GROUPS = ("archive200", "skipping", "plain", "archive", "octax", "ours", "all")


def select_games(spec: str) -> list[str]:
    import octax_core

    if spec == "all":
        return octax_core.list_games()
    if spec == "archive200":
        return [g for g in octax_core.list_games("archive") if game_ipf(g) >= 200]
    if spec in ("skipping", "plain"):  # where skip_idle takes effect (>= idle.SKIP_FROM ipf), and the rest
        from octax_core.emulator.idle import SKIP_FROM

        return [g for g in octax_core.list_games() if (game_ipf(g) >= SKIP_FROM) == (spec == "skipping")]
    if spec in ("archive", "octax", "ours"):
        return octax_core.list_games(spec)
    games = [g.strip() for g in spec.split(",") if g.strip()]
    for game in games:
        octax_core.get_spec(game)  # raises KeyError naming the valid ids
    return games


def game_ipf(game: str) -> int:
    """The instructions per frame `make(game)` runs at: the game's own, else the env default."""
    from octax_core.env.config import make_config
    from octax_core.env.games import get_spec

    return make_config(get_spec(game))[0].instructions_per_frame


def prepare(game: str, skip_idle: bool, num_envs: int, steps: int, seed: int) -> tuple[Prepared, dict, object]:
    """One side, compiled: its `Prepared` (whose run also keeps its latest output in `outputs`,
    every run's being the same) and the env."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    import octax_core

    env, params = octax_core.make(game, autoreset=True, skip_idle=skip_idle)
    weights = jnp.asarray(np.random.default_rng(0).integers(1, 2**31, env.observation_shape), jnp.uint32)

    def rollout(start, keys, actions, fingerprints: bool):
        """`steps` env steps from `start`: the timed run carries each step's observation (so its
        work is kept) and returns the rewards, flags and scores; the check run (untimed) also
        returns a fingerprint of every step's observation. Weighting 32 K pixels a step costs
        more than a low-ipf game's whole step, so it stays out of the timing."""
        def step(carry, inputs):
            _, state = carry
            keys, action = inputs
            obs, state, reward, terminated, truncated, info = jax.vmap(env.step, in_axes=(0, 0, 0, None))(
                keys, state, action, params)
            out = (reward, terminated, truncated, info["score"])
            if fingerprints:
                out += (jnp.sum(obs.astype(jnp.uint32) * weights, axis=(1, 2, 3), dtype=jnp.uint32),)
            return (obs, state), out
        return jax.lax.scan(step, start, (keys, actions))

    actions = np.random.default_rng(seed).integers(0, env.num_actions, (steps, num_envs), dtype=np.int32)
    key = jax.random.key(seed)
    keys = jax.random.split(jax.random.fold_in(key, 1), (steps, num_envs))
    start = jax.jit(jax.vmap(env.reset, in_axes=(0, None)))(jax.random.split(key, num_envs), params)
    t0 = time.perf_counter()
    compiled = jax.jit(functools.partial(rollout, fingerprints=False),
                       compiler_options=env.compiler_options).lower(start, keys, actions).compile()
    compile_s = time.perf_counter() - t0
    outputs = {"checked": jax.jit(functools.partial(rollout, fingerprints=True),
                                  compiler_options=env.compiler_options)(start, keys, actions)}

    def run():
        outputs["last"] = compiled(start, keys, actions)
        return outputs["last"]

    side = Prepared(run=run, compile_s=compile_s, state_bytes=0,
                    instructions_per_step=env.config.frames_per_step * env.config.instructions_per_frame)
    return side, outputs, env


def measure(game: str, num_envs: int, steps: int, repeats: int, seed: int) -> dict:
    import jax
    import numpy as np

    from octax_core.env import suite_of

    sides, outputs = {}, {}
    for skip_idle in (False, True):
        sides[skip_idle], outputs[skip_idle], env = prepare(game, skip_idle, num_envs, steps, seed)
    time_interleaved(sides, repeats, Progress(0, enabled=False), game)
    exact = all(np.array_equal(np.asarray(a), np.asarray(b))
                for run in ("last", "checked")
                for a, b in zip(jax.tree.leaves(outputs[False][run]), jax.tree.leaves(outputs[True][run])))
    plain_sps = steps * num_envs / sides[False].best_s
    skip_sps = steps * num_envs / sides[True].best_s
    return dict(game=game, suite=suite_of(game), platform=env.spec.platform, ipf=env.config.instructions_per_frame,
                n=num_envs, steps=steps, plain_sps=round(plain_sps), skip_sps=round(skip_sps),
                speedup=round(skip_sps / plain_sps, 3), exact=exact,
                compile_plain_s=round(sides[False].compile_s, 2), compile_skip_s=round(sides[True].compile_s, 2))


def geomean(values) -> float:
    values = list(values)
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else float("nan")


def summaries(rows: list[dict]) -> list[dict]:
    out = []
    for n in sorted({r["n"] for r in rows}):
        at_n = [r for r in rows if r["n"] == n]
        groups = {"archive200": [r for r in at_n if r["suite"] == "archive" and r["ipf"] >= 200], "measured": at_n}
        for group, members in groups.items():
            if members:
                out.append(dict(group=group, n=n, games=len(members),
                                geomean_speedup=round(geomean(r["speedup"] for r in members), 3),
                                min_speedup=min(r["speedup"] for r in members),
                                max_speedup=max(r["speedup"] for r in members),
                                exact="all" if all(r["exact"] for r in members) else "NOT"))
    return out


FOOTNOTE = ("Games under 25 instructions a frame (`octax_core.emulator.idle.SKIP_FROM`: the octax suite's games "
            "at 11, most archive games at 7 to 20) run the same plain program with skip_idle on or off, so their "
            "speed does not change, and the larger N (`--skipping-envs`, a `-` in their rows) is measured only "
            "on the games where it takes effect. Timings on the shared 2-core machine vary by "
            "about +-10% from run to run; each row's two sides are timed alternately.")


def markdown(rows: list[dict]) -> str:
    ns = sorted({r["n"] for r in rows})
    by_game = {}
    for r in rows:
        by_game.setdefault(r["game"], {})[r["n"]] = r
    lines = [
        "# Speed with and without skip_idle",
        "",
        "Generated by `benchmarks/skip_idle.py` (do not edit by hand), from the rows of:",
        "",
        *[f"    {command}" for command in dict.fromkeys(r.get("command", "(command not recorded)") for r in rows)],
        "",
        f"Machine: {platform.processor() or platform.machine()}, {_cores()} cores, CPU only; "
        f"JAX {_jax_version()}; XLA:CPU's thread pool as each command gives it (JAX's default: a thread a core). "
        "Env steps per second (4 frames a step, random actions, same-step autoreset), "
        "best of the timed runs; `exact`: every step's observation, reward and flags, and the final state, "
        "equal with and without skip_idle. docs/machine.md says what skip_idle detects.",
        "",
    ]
    head = "| game | suite | platform | ipf | " + " | ".join(f"N={n} off | N={n} on | N={n} x" for n in ns) + " | exact |"
    lines += [head, "|" + "---|" * (head.count("|") - 1)]
    for game in sorted(by_game, key=lambda g: (-by_game[g][ns[0]]["ipf"] if ns[0] in by_game[g] else 0, g)):
        cells = by_game[game]
        first = next(iter(cells.values()))
        parts = [game, first["suite"], first["platform"], str(first["ipf"])]
        for n in ns:
            r = cells.get(n)
            parts += ([f"{r['plain_sps']:,}", f"{r['skip_sps']:,}", f"{r['speedup']:.2f}"] if r else ["", "", ""])
        parts.append("yes" if all(r["exact"] for r in cells.values()) else "NO")
        parts = [p if p else "-" for p in parts]
        lines.append("| " + " | ".join(parts) + " |")
    lines += ["", "| group | N | games | geometric-mean speed-up | min | max | exact |", "|---|---|---|---|---|---|---|"]
    for s in summaries(rows):
        lines.append(f"| {s['group']} | {s['n']} | {s['games']} | {s['geomean_speedup']:.2f} | {s['min_speedup']:.2f} | "
                     f"{s['max_speedup']:.2f} | {s['exact']} |")
    lines += ["", FOOTNOTE]
    return "\n".join(lines) + "\n"


def _cores() -> int:
    import os

    return os.cpu_count() or 0


def _jax_version() -> str:
    import jax

    return jax.__version__


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--games", default="all",
                        help=f"comma-separated ids, or one of {', '.join(GROUPS)} (default all)")
    parser.add_argument("--envs", default="64", help="comma-separated batch sizes N (default 64)")
    parser.add_argument("--skipping-envs", default="",
                        help="more batch sizes, measured only on the games where skip_idle takes effect "
                             "(>= idle.SKIP_FROM instructions a frame; the others run the same program either way)")
    parser.add_argument("--skipping-steps", type=int, default=None,
                        help="env steps per timed run at the --skipping-envs sizes (default: --steps)")
    parser.add_argument("--steps", type=int, default=40, help="env steps per timed run (default 40)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per side, the best counts (default 3)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jsonl", type=Path, default=None, help="also append each row, as JSON, to this file")
    parser.add_argument("--markdown", type=Path, default=None, help="write the table page (e.g. docs/speed.md)")
    parser.add_argument("--include", type=Path, action="append", default=[],
                        help="rows of an earlier run (its --jsonl file) to put on the page too; a later --include, "
                             "then this run, replaces an earlier row for the same game and N")
    args = parser.parse_args(argv)
    given = list(argv if argv is not None else sys.argv[1:])
    for local in ("--jsonl", "--include"):  # where rows were copied or merged from: not what was measured
        while local in given:
            del given[given.index(local):given.index(local) + 2]
    threads = os.environ.get("OCTAX_CPU_THREADS")  # XLA:CPU's pool (octax_core.host), part of how it ran
    command = " ".join(([f"OCTAX_CPU_THREADS={threads}"] if threads else []) + ["python benchmarks/skip_idle.py"] + given)
    games = select_games(args.games)
    ns = [int(n) for n in args.envs.split(",")]
    more = [int(n) for n in args.skipping_envs.split(",") if n.strip()]
    rows = []
    print(f"# {len(games)} games, N = {ns}, {args.steps} steps, best of {args.repeats}; load {load_average():.2f}",
          flush=True)
    from octax_core.emulator.idle import SKIP_FROM

    for game in games:
        skipping = game_ipf(game) >= SKIP_FROM
        for n in ns + (more if skipping else []):
            steps = args.skipping_steps if n in more and n not in ns and args.skipping_steps else args.steps
            row = measure(game, n, steps, args.repeats, args.seed)
            row["command"] = command
            rows.append(row)
            print(bench_line("skip_idle", {k: v for k, v in row.items() if k != "command"}), flush=True)
            if args.jsonl:
                with args.jsonl.open("a") as f:
                    f.write(json.dumps(row) + "\n")
    for s in summaries(rows):
        print(bench_line("skip_idle_summary", s), flush=True)
    if args.markdown:
        earlier = [json.loads(line) for path in args.include for line in path.read_text().splitlines() if line.strip()]
        merged = {}  # a later include, then this run, replaces an earlier row for the same game and N
        for row in earlier + rows:
            merged[(row["game"], row["n"])] = row
        page_rows = list(merged.values())
        if args.include:
            for s in summaries(page_rows):
                print(bench_line("skip_idle_summary_page", s), flush=True)
        args.markdown.write_text(markdown(page_rows))
    return 0 if all(r["exact"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
