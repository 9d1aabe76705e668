"""What the env loop costs on top of the bare machine: autoreset, no-op starts, sticky actions.

The ALE protocol an RL trainer follows (Machado et al., 2018) resets each episode with up to 30
no-op steps and repeats the previous action with probability 0.25. Here Pong runs N envs for
100 steps of 4 frames x 11 instructions, key 1 held, in one process:

    machine          the bare machine (`Machine.run_frames`), as `throughput.py --mode machine`
    env              the functional env, `octax_core.make("Pong", autoreset=True, noop_max=M,
                     repeat_action_probability=P)`, scanned as `throughput.py --mode env`
    gym              the Gymnasium vector env with the same keywords (NEXT_STEP autoreset), stepped
                     from Python with numpy actions (`--layers env,gym`)
    octax            the octax package's step with gymnax's autoreset (a reset for every env every
                     step, then a select), no no-op starts or sticky actions: it has neither

Every side runs the same frames (4 x 11 instructions a step); each env case prints one
`BENCH env_loop` line whose `vs_machine` is its steps/s over the machine's, timed interleaved.

    python benchmarks/env_loop.py                          # N = 512, noop_max 0 and 30, sticky 0.25
    python benchmarks/env_loop.py --envs 64,512 --layers env,gym --no-octax
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Optional

import octax_side
from harness import (DEFAULT_ROM_DIR, BenchError, Progress, bench_line, find_rom, load_average, machine_line,
                     time_interleaved)
from throughput import GAME, prepare_env, prepare_gym, prepare_machine

LAYERS = ("env", "gym")


def main(argv: Optional[list[str]] = None, *, prog: Optional[str] = None, progress: bool = False) -> int:
    parser = argparse.ArgumentParser(prog=prog, description=__doc__.splitlines()[0])
    parser.add_argument("--envs", default="512", help="comma-separated batch sizes N (default 512)")
    parser.add_argument("--noop-max", default="0,30", help="comma-separated noop_max values (default 0,30)")
    parser.add_argument("--sticky", type=float, default=0.25,
                        help="repeat_action_probability of the env cases (default 0.25)")
    parser.add_argument("--layers", default="env", help=f"comma-separated, of {', '.join(LAYERS)} (default env)")
    parser.add_argument("--max-episode-steps", type=int, default=None,
                        help="truncate episodes after this many steps, so that envs end (and reset) during "
                             "the timed runs (default: Pong's own 4500, which a 100-step run never reaches)")
    parser.add_argument("--steps", type=int, default=100, help="env steps per timed run (default 100)")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per side; the best is kept (default 5)")
    parser.add_argument("--no-octax", action="store_true", help="skip the octax comparison")
    parser.add_argument("--rom", type=Path, default=None,
                        help=f"Pong ROM file or folder (default: the ROM store, then $OCTAX_ROM_DIR or {DEFAULT_ROM_DIR})")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=progress,
                        help="a progress bar on stderr")
    args = parser.parse_args(argv)
    try:
        args.envs = [int(n) for n in args.envs.split(",")]
        args.noop_max = [int(n) for n in args.noop_max.split(",")]
    except ValueError:
        parser.error("--envs and --noop-max take comma-separated integers")
    args.layers = args.layers.split(",")
    if set(args.layers) - set(LAYERS) or min(args.envs) < 1 or min(args.noop_max) < 0:
        parser.error(f"--layers takes {', '.join(LAYERS)}; --envs must be >= 1 and --noop-max >= 0")
    if args.steps < 1 or args.repeats < 1 or not 0 <= args.sticky <= 1:
        parser.error("--steps and --repeats must be >= 1, --sticky in [0, 1]")
    args.key, args.devices, args.backend = 1, 1, "numpy"  # what the shared prepare functions read
    from octax_core.env import romstore

    try:
        return run(args)
    except (BenchError, romstore.RomNotFoundError, romstore.RomHashError) as exc:
        print(f"{parser.prog}: error: {exc}", file=sys.stderr)
        return 1


def run(args: argparse.Namespace) -> int:
    import jax

    rom = find_rom(GAME, args.rom)
    print(machine_line(rom), flush=True)
    if not args.no_octax and (why := octax_side.import_error()) is not None:
        print(f"# octax comparison skipped: cannot import octax ({why})", flush=True)
        args.no_octax = True
    cases = [(layer, noop_max) for layer in args.layers for noop_max in args.noop_max]
    sides_per_n = 1 + len(cases) + (not args.no_octax)
    progress = Progress(len(args.envs) * sides_per_n * (2 + args.repeats), args.progress)
    try:
        for n in args.envs:
            _bench_one(rom, n, cases, args, jax.default_backend(), progress)
    finally:
        progress.close()
    return 0


def _bench_one(rom: Path, n: int, cases, args: argparse.Namespace, device: str, progress: Progress) -> None:
    prepare = {"env": prepare_env, "gym": prepare_gym}
    progress.stage(f"n={n} machine: compile")
    sides = {"machine": prepare_machine(rom, n, args)}
    progress.advance()
    for layer, noop_max in cases:
        progress.stage(f"n={n} {layer} noop_max={noop_max}: compile")
        options = {"noop_max": noop_max, "repeat_action_probability": args.sticky,
                   "max_episode_steps": args.max_episode_steps}
        if layer == "env":
            options["autoreset"] = True
        sides[f"{layer}-noop{noop_max}"] = prepare[layer](rom, n, args, **options)
        progress.advance()
    if not args.no_octax:
        progress.stage(f"n={n} octax: compile")
        sides["octax"] = octax_side.prepare(rom, n, args, autoreset=True, max_episode_steps=args.max_episode_steps)
        progress.advance()
    time_interleaved(sides, args.repeats, progress, f"n={n}")
    sps = {name: n * args.steps / side.best_s for name, side in sides.items()}
    load = load_average()
    for name, side in sides.items():
        progress.print(f"{name:12s} n={n}: {sps[name]:,.0f} env steps/s, compile {side.compile_s:.2f} s, "
                       f"{side.state_bytes} B/env, load {load:.2f}")
    for layer, noop_max in cases:
        name = f"{layer}-noop{noop_max}"
        fields = {"layer": layer, "n": n, "steps": args.steps, "autoreset": 1, "noop_max": noop_max,
                  "sticky": args.sticky, "max_episode_steps": args.max_episode_steps or "game",
                  "sps": round(sps[name]), "machine_sps": round(sps["machine"]),
                  "vs_machine": round(sps[name] / sps["machine"], 3), "state_bytes": sides[name].state_bytes,
                  "compile_s": round(sides[name].compile_s, 2),
                  "octax_sps": round(sps["octax"]) if "octax" in sps else None,
                  "ratio": round(sps[name] / sps["octax"], 2) if "octax" in sps else None, "device": device}
        progress.print(bench_line("env_loop", fields))


if __name__ == "__main__":
    sys.exit(main())
