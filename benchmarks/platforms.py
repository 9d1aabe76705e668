"""Throughput per platform: CHIP-8, SUPER-CHIP and XO-CHIP machines on the same kind of work.

For each platform, N machines run a game's ROM for `--steps` env steps of 4 frames, a constant
key held, in one jitted scan of the vmapped `Machine.run_frames` (as `throughput.py --mode
machine` does for Pong), best of `--repeats` timed runs, compile time excluded:

    chip8   Pong (the octax suite's ROM, from the ROM store), 11 instructions a frame, as the
            octax paper measures it; octax runs the same work, and the ratio is reported
    schip   a hires SUPER-CHIP game of the Chip8 Community Archive, which ships in the package
            (octax_core/env/roms/archive/; default blackrainbow)
    xochip  a hires XO-CHIP game of the archive (default civiliz8n)

The archive games run under their own programs.json quirks and tick rate (instructions a frame),
so `ips` (instructions per second) is the figure to compare across platforms; `sps` is env steps
per second. Each (platform, N) prints exactly one summary line starting with ``BENCH platforms``;
`state_bytes` is one machine's state.

    python benchmarks/platforms.py                      # N = 512, all three, octax on chip8
    python benchmarks/platforms.py --envs 64,512 --platforms schip,xochip --no-octax

`--same-program` measures what a platform costs by itself: one CHIP-8 program run by a chip8, an
schip and an xochip `Machine` with the same quirks and instructions per frame, the three timed
alternately in one process, and prints each platform's instructions/s and its ratio to chip8,
one ``BENCH same_program`` line per (program, N, platform). The programs: Pong (11 ipf, the
chip8 quirks) and a 15-ipf CHIP-8 game of the archive (`--archive-chip8-game`, its own quirks).

    python benchmarks/platforms.py --same-program --envs 64,512
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Optional

import octax_side
from harness import (BenchError, Prepared, Progress, bench_line, compile_rollout, find_rom, load_average,
                     machine_line, state_bytes, time_interleaved)

PLATFORMS = ("chip8", "schip", "xochip")
FRAMES_PER_STEP = 4
CHIP8_GAME, CHIP8_INSTRUCTIONS_PER_FRAME = "Pong", 11
def _packaged_archive() -> Path:
    from octax_core.env.romstore import ARCHIVE_ROM_DIR  # the archive ships in the package

    return ARCHIVE_ROM_DIR
DEFAULT_GAMES = {"schip": "blackrainbow", "xochip": "civiliz8n"}
SAME_PROGRAM_ARCHIVE_GAME = "carbon8"  # CHIP-8, 15 instructions a frame


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", default="512", help="comma-separated batch sizes N (default 512)")
    parser.add_argument("--platforms", default=",".join(PLATFORMS), help="comma-separated subset of chip8,schip,xochip")
    parser.add_argument("--steps", type=int, default=50, help="env steps per timed run (default 50)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per side, the best counts (default 3)")
    parser.add_argument("--key", type=int, default=-1, help="CHIP-8 key held throughout, -1 for none (default)")
    parser.add_argument("--schip-game", default=DEFAULT_GAMES["schip"], help="archive program name for schip")
    parser.add_argument("--xochip-game", default=DEFAULT_GAMES["xochip"], help="archive program name for xochip")
    parser.add_argument("--archive", type=Path, default=None,
                        help="folder with the archive's ROMs and programs.json (default: the package's copy)")
    parser.add_argument("--no-octax", action="store_true", help="skip the octax comparison on chip8")
    parser.add_argument("--same-program", action="store_true",
                        help="run one CHIP-8 program on every platform (same quirks and ipf) and report the ratios")
    parser.add_argument("--archive-chip8-game", default=SAME_PROGRAM_ARCHIVE_GAME,
                        help=f"the archive's CHIP-8 program for --same-program (default {SAME_PROGRAM_ARCHIVE_GAME})")
    args = parser.parse_args(argv)
    try:
        args.envs = [int(n) for n in args.envs.split(",")]
        args.platforms = [p.strip() for p in args.platforms.split(",")]
    except ValueError:
        parser.error(f"--envs must be comma-separated positive integers, got {args.envs!r}")
    if min(args.envs) < 1 or args.steps < 1 or args.repeats < 1 or not -1 <= args.key <= 15:
        parser.error("--envs, --steps and --repeats must be >= 1 and --key in -1..15")
    if unknown := [p for p in args.platforms if p not in PLATFORMS]:
        parser.error(f"unknown platform(s) {unknown}; valid: {', '.join(PLATFORMS)}")
    args.devices = 1  # octax_side reads it
    args.archive = args.archive or _packaged_archive()
    try:
        return run_same_program(args) if args.same_program else run(args)
    except (BenchError, FileNotFoundError, KeyError) as exc:
        print(f"{parser.prog}: error: {exc}", file=sys.stderr)
        return 1


def workload(platform: str, args: argparse.Namespace):
    """(game name, ROM path, Machine) for `platform`."""
    import octax_core
    from octax_core.emulator.quirks import quirks_from_octo

    if platform == "chip8":
        return CHIP8_GAME, find_rom(CHIP8_GAME, None), octax_core.Machine(
            "chip8", instructions_per_frame=CHIP8_INSTRUCTIONS_PER_FRAME)
    game = args.schip_game if platform == "schip" else args.xochip_game
    manifest = args.archive / "programs.json"
    if not manifest.is_file():
        raise BenchError(f"no {manifest}: the archive's programs are needed for {platform} (see --archive)")
    entry = json.loads(manifest.read_text()).get(game)
    if entry is None or entry["platform"] != platform:
        raise BenchError(f"{game!r} is not a {platform} program of the archive")
    options = entry["options"]
    machine = octax_core.Machine(platform, quirks=quirks_from_octo(options),
                                 instructions_per_frame=int(options.get("tickrate", 20)))
    return game, args.archive / f"{game}.ch8", machine


def prepare(machine, rom: Path, n: int, args: argparse.Namespace) -> Prepared:
    """vmapped `machine.run_frames(state, keys, 4)`, scanned `steps` times."""
    import jax
    import jax.numpy as jnp

    rom_bytes = rom.read_bytes()
    states = jax.vmap(lambda k: machine.boot(rom_bytes, k))(jax.random.split(jax.random.key(0), n))
    actions = jnp.full((n,), 0 if args.key < 0 else 1 << args.key, dtype=jnp.int32)
    step = jax.vmap(lambda s, k: machine.run_frames(s, k, FRAMES_PER_STEP))

    def rollout(states, actions):
        return jax.lax.scan(lambda s, _: (step(s, actions), None), states, length=args.steps)[0]

    run, compile_s, devices = compile_rollout(rollout, states, actions, compiler_options=machine.compiler_options)
    return Prepared(run, compile_s, state_bytes(states), FRAMES_PER_STEP * machine.instructions_per_frame, devices)


def run(args: argparse.Namespace) -> int:
    import jax

    loads = {platform: workload(platform, args) for platform in args.platforms}  # fail before compiling
    print(machine_line(loads[args.platforms[0]][1]), flush=True)
    octax = "chip8" in args.platforms and not args.no_octax
    if octax and (why := octax_side.import_error()) is not None:
        print(f"# octax comparison skipped: cannot import octax ({why}); pip install 'octax-gym[dev]'", flush=True)
        octax = False
    progress = Progress(0, False)
    for n in args.envs:
        for platform, (game, rom, machine) in loads.items():
            sides = {platform: prepare(machine, rom, n, args)}
            if platform == "chip8" and octax:
                sides["octax"] = octax_side.prepare(rom, n, args)
            time_interleaved(sides, args.repeats, progress, f"n={n}")
            ours, theirs = sides[platform], sides.get("octax")
            sps = n * args.steps / ours.best_s
            octax_sps = n * args.steps / theirs.best_s if theirs else None
            print(f"{platform:6s} {game} n={n}: {sps:,.0f} steps/s, {sps * ours.instructions_per_step / 1e6:,.1f} M instr/s, "
                  f"{ours.state_bytes} B/machine, compile {ours.compile_s:.2f} s, load {load_average():.2f}", flush=True)
            print(bench_line("platforms", {
                "platform": platform, "game": game, "n": n, "steps": args.steps,
                "instructions_per_frame": machine.instructions_per_frame, "sps": round(sps),
                "ips": round(sps * ours.instructions_per_step), "state_bytes": ours.state_bytes,
                "compile_s": round(ours.compile_s, 2), "octax_sps": round(octax_sps) if theirs else None,
                "ratio": round(sps / octax_sps, 2) if theirs else None, "device": jax.default_backend(),
            }), flush=True)
    return 0


def same_programs(args: argparse.Namespace) -> list[tuple[str, Path, object, int]]:
    """(name, ROM path, quirks, instructions per frame) of the CHIP-8 programs --same-program runs."""
    from octax_core.emulator.quirks import quirks_from_octo, resolve_quirks

    manifest = args.archive / "programs.json"
    entry = json.loads(manifest.read_text()).get(args.archive_chip8_game) if manifest.is_file() else None
    if entry is None or entry["platform"] != "chip8":
        raise BenchError(f"{args.archive_chip8_game!r} is not a CHIP-8 program of the archive at {args.archive}")
    options = entry["options"]
    return [(CHIP8_GAME, find_rom(CHIP8_GAME, None), resolve_quirks("chip8"), CHIP8_INSTRUCTIONS_PER_FRAME),
            (args.archive_chip8_game, args.archive / f"{args.archive_chip8_game}.ch8", quirks_from_octo(options),
             int(options.get("tickrate", 20)))]


def run_same_program(args: argparse.Namespace) -> int:
    """Each program, each N: the platforms timed alternately on the same work."""
    import jax

    import octax_core

    programs = same_programs(args)
    print(machine_line(programs[0][1]), flush=True)
    progress = Progress(0, False)
    for name, rom, quirks, ipf in programs:
        for n in args.envs:
            sides = {platform: prepare(octax_core.Machine(platform, quirks=quirks, instructions_per_frame=ipf), rom, n,
                                       args) for platform in args.platforms}
            time_interleaved(sides, args.repeats, progress, f"{name} n={n}")
            ips = {platform: n * args.steps * side.instructions_per_step / side.best_s for platform, side in sides.items()}
            base = ips.get("chip8")
            for platform, side in sides.items():
                ratio = ips[platform] / base if base else None
                print(f"{name} n={n} {platform:6s}: {ips[platform] / 1e6:,.2f} M instr/s"
                      + (f", {ratio:.2f}x chip8" if ratio else "") + f", compile {side.compile_s:.2f} s", flush=True)
                print(bench_line("same_program", {
                    "program": name, "n": n, "platform": platform, "steps": args.steps,
                    "instructions_per_frame": ipf, "ips": round(ips[platform]),
                    "ratio": round(ratio, 3) if ratio else None, "compile_s": round(side.compile_s, 2),
                    "load": round(load_average(), 2), "device": jax.default_backend(),
                }), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
