"""Throughput on Pong, ours against the `octax` package on the same work (also `octax-gym bench`).

The workload is the one of the octax paper: Pong, a constant action, N envs, 100 env steps of
4 frames x 11 instructions, best of several timed runs, compile time excluded. Each N prints
free-form lines, then exactly one summary line starting with ``BENCH throughput``. Modes:

    machine   `Machine.run_frames` alone, scanned in one jitted call
    env       the functional env (`octax_core.make("Pong")`): observation, reward, key splits
    gym       the Gymnasium vector env (`gym.make_vec("octax/Pong-v0", ...)`): one Python call
              per step, actions checked and outputs converted to the `--backend` arrays

    python benchmarks/throughput.py                    # N = 1, 64, 512, 2048, 8192, with octax
    python benchmarks/throughput.py --quick            # N = 64, 512, 2 repeats (smoke test)
    python benchmarks/throughput.py --envs 512 --devices 2 --no-octax
    python benchmarks/throughput.py --mode gym --backend torch

`--devices D` splits the batch over D XLA host devices (`harness.set_host_devices`, which must
run before JAX computes anything; `octax-gym bench` imports JAX first, and that is fine). See
benchmarks/README.md for the output fields.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Optional

import octax_side
from harness import (DEFAULT_ROM_DIR, BenchError, Prepared, Progress, bench_line, compile_rollout, find_rom,
                     load_average, machine_line, set_host_devices, state_bytes, time_interleaved)

GAME = "Pong"
FRAMES_PER_STEP = 4
INSTRUCTIONS_PER_FRAME = 11
QUIRKS = "chip8"
MODES = ("machine", "env", "gym")
BACKENDS = ("numpy", "jax", "torch")
ALL_ENVS, QUICK_ENVS = "1,64,512,2048,8192", "64,512"
ALL_REPEATS, QUICK_REPEATS = 5, 2


def main(argv: Optional[list[str]] = None, *, prog: Optional[str] = None, progress: bool = False) -> int:
    """Parses `argv`, runs, returns the exit status (1: an error reported on stderr).

    `prog` and `progress` (the default of `--progress`) let `octax-gym bench` present it as its own.
    """
    parser = argparse.ArgumentParser(prog=prog, description=__doc__.splitlines()[0])
    add_arguments(parser, progress=progress)
    args = check_args(parser, parser.parse_args(argv))
    from octax_core.env import romstore  # imports JAX, which is fine: nothing has been computed yet

    try:
        return run(args)
    except (BenchError, romstore.RomNotFoundError, romstore.RomHashError) as exc:
        print(f"{parser.prog}: error: {exc}", file=sys.stderr)
        return 1


def add_arguments(p: argparse.ArgumentParser, *, progress: bool = False) -> None:
    """The benchmark's options; `progress` is the default of `--progress/--no-progress`."""
    p.add_argument("--mode", choices=MODES, default="machine",
                   help="machine: Machine.run_frames alone; env: octax_core.make('Pong') reset + step, "
                        "observation (4 frames, uint8) and reward included; gym: gym.make_vec("
                        "'octax/Pong-v0') stepped from Python, host conversions included (default machine)")
    p.add_argument("--envs", default=None, help=f"comma-separated batch sizes N (default {ALL_ENVS})")
    p.add_argument("--backend", choices=BACKENDS, default=None,
                   help="gym mode: the arrays the vector env takes and hands out (default numpy)")
    p.add_argument("--steps", type=int, default=100, help="env steps per timed run (default 100)")
    p.add_argument("--repeats", type=int, default=None,
                   help=f"timed runs per N; the best is kept (default {ALL_REPEATS})")
    p.add_argument("--key", type=int, default=1,
                   help="CHIP-8 key held for the whole run, 0..15, or -1 for none (default 1: octax "
                        "Pong's action 0, as in its paper benchmark, and action 1 of octax/Pong-v0)")
    p.add_argument("--devices", type=int, default=1,
                   help="machine and env modes: split the batch over this many XLA host devices "
                        "with shard_map (default 1)")
    p.add_argument("--no-octax", action="store_true", help="skip the octax comparison")
    p.add_argument("--octax-max-envs", type=int, default=0,
                   help="run octax only for N up to this (its compile time grows with N; 0 = no cap)")
    p.add_argument("--quick", action="store_true",
                   help=f"a smoke test: N = {QUICK_ENVS} and {QUICK_REPEATS} repeats, unless --envs "
                        "or --repeats says otherwise")
    p.add_argument("--rom", type=Path, default=None,
                   help=f"Pong ROM file or folder (default: the ROM store, see docs/roms.md, then "
                        f"$OCTAX_ROM_DIR or {DEFAULT_ROM_DIR} from the repository root)")
    p.add_argument("--jsonl", type=Path, default=None, help="also append one JSON object per N to this file")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=progress,
                   help="a progress bar on stderr; stdout stays machine-readable "
                        f"(default {'on' if progress else 'off'})")


def check_args(p: argparse.ArgumentParser, args: argparse.Namespace) -> argparse.Namespace:
    """Fills the --quick defaults and checks the values; `p.error` (exit status 2) on a bad one."""
    envs = args.envs if args.envs is not None else (QUICK_ENVS if args.quick else ALL_ENVS)
    if args.repeats is None:
        args.repeats = QUICK_REPEATS if args.quick else ALL_REPEATS
    try:
        args.envs = [int(n) for n in envs.split(",") if n.strip()]
    except ValueError:
        p.error(f"--envs must be comma-separated positive integers, got {envs!r}")
    if not args.envs or min(args.envs) < 1:
        p.error(f"--envs must be positive integers, got {envs!r}")
    if args.steps < 1 or args.repeats < 1 or args.devices < 1:
        p.error("--steps, --repeats and --devices must be >= 1")
    if not -1 <= args.key <= 15:
        p.error(f"--key must be in -1..15, got {args.key}")
    if args.mode == "gym":
        args.backend = args.backend or "numpy"
        if args.devices != 1:
            p.error("--mode gym runs the vector env on one device: --devices must be 1")
    elif args.backend is not None:
        p.error(f"--backend applies to --mode gym only, not to --mode {args.mode}")
    return args


def prepare_machine(rom: Path, n: int, args: argparse.Namespace) -> Prepared:
    """Our core: vmapped `Machine.run_frames(state, keys, 4)`, scanned `steps` times."""
    import jax
    import jax.numpy as jnp
    import octax_core

    machine = octax_core.Machine(quirks=QUIRKS, instructions_per_frame=INSTRUCTIONS_PER_FRAME)
    rom_bytes = rom.read_bytes()
    states = jax.vmap(lambda k: machine.boot(rom_bytes, k))(jax.random.split(jax.random.key(0), n))
    # Key masks are data, as actions from a policy would be: nothing constant-folds the key checks.
    mask = 0 if args.key < 0 else 1 << args.key
    actions = jnp.full((n,), mask, dtype=jnp.int32)
    step = jax.vmap(lambda s, k: machine.run_frames(s, k, FRAMES_PER_STEP))

    def rollout(states, actions):
        states, _ = jax.lax.scan(lambda s, _: (step(s, actions), None), states, length=args.steps)
        return states

    run, compile_s, devices = compile_rollout(rollout, states, actions, args.devices, machine.compiler_options)
    return Prepared(run, compile_s, state_bytes(states), FRAMES_PER_STEP * INSTRUCTIONS_PER_FRAME, devices)


def prepare_env(rom: Path, n: int, args: argparse.Namespace, **overrides) -> Prepared:
    """Our functional env: vmapped `env.step(key, state, action, params)`, scanned `steps` times.

    Each step produces the (4, 32, 64) uint8 observation, the reward and the flags, and splits
    its key, as an RL loop does; the observation rides in the carry so none of it is dropped.
    `overrides` go to `octax_core.make` (benchmarks/env_loop.py passes autoreset and no-op starts).
    """
    import jax
    import jax.numpy as jnp
    import octax_core

    env, params = octax_core.make(GAME, rom=rom, frames_per_step=FRAMES_PER_STEP,
                                  instructions_per_frame=INSTRUCTIONS_PER_FRAME, **overrides)
    keys = jax.random.split(jax.random.key(0), n)
    obs, states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
    actions = jnp.full((n,), our_action(env.spec.action_keys, args.key), dtype=jnp.int32)
    step = jax.vmap(env.step, in_axes=(0, 0, 0, None))

    def rollout(carry, actions):
        def body(carry, _):
            keys, states, _ = carry
            keys, step_keys = jnp.split(jax.vmap(jax.random.split)(keys), 2, axis=1)
            obs, states, *_ = step(step_keys[:, 0], states, actions, params)
            return (keys[:, 0], states, obs), None
        carry, _ = jax.lax.scan(body, carry, length=args.steps)
        return carry

    run, compile_s, devices = compile_rollout(rollout, (keys, states, obs), actions, args.devices,
                                              env.compiler_options)
    return Prepared(run, compile_s, state_bytes(states), FRAMES_PER_STEP * INSTRUCTIONS_PER_FRAME, devices)


def prepare_gym(rom: Path, n: int, args: argparse.Namespace, **overrides) -> Prepared:
    """The Gymnasium vector env: `steps` calls of `envs.step(actions)`, from Python.

    Each call checks the actions, runs one jitted step (key split, batched step, autoreset) and
    hands obs, reward, flags and info over as `--backend` arrays, as an RL loop sees them. The
    actions are a fixed array of that backend. Every timed run starts from `reset(seed=0)`
    (untimed), so all runs do the same work. `overrides` are more `make_vec` keywords.
    """
    import time

    import gymnasium as gym
    import jax
    import numpy as np

    from octax_gym.registration import env_id

    envs = gym.make_vec(env_id(GAME), num_envs=n, backend=args.backend, rom=rom,
                        frames_per_step=FRAMES_PER_STEP, instructions_per_frame=INSTRUCTIONS_PER_FRAME, **overrides)
    core = envs.unwrapped.core_env
    actions = np.full((n,), our_action(core.spec.action_keys, args.key), np.int32)
    if args.backend != "numpy":  # where a policy's actions would be: on the env's device
        actions = jax.device_put(actions, envs.unwrapped.device)
    if args.backend == "torch":
        import torch

        actions = torch.from_dlpack(actions)

    def run():
        for _ in range(args.steps):
            envs.step(actions)
        return envs.unwrapped.state  # computed by the same call as the outputs: ready means all ready

    t0 = time.perf_counter()
    envs.reset(seed=0)
    envs.step(actions)  # compiles the step for this N
    jax.block_until_ready(envs.unwrapped.state)
    compile_s = time.perf_counter() - t0
    config = core.config
    return Prepared(run, compile_s, state_bytes(envs.unwrapped.state),
                    config.frames_per_step * config.instructions_per_frame, 1,
                    setup=lambda: envs.reset(seed=0))


def our_action(action_keys: tuple[int, ...], key: int) -> int:
    """The action holding CHIP-8 `key` (0 = none), or BenchError when the game has no such action."""
    if key < 0:
        return 0
    if key not in action_keys:
        raise BenchError(f"{GAME} has no action for key {key} (keys {list(action_keys)}); use --key -1 or one of them")
    return list(action_keys).index(key) + 1


PREPARE = {"machine": prepare_machine, "env": prepare_env, "gym": prepare_gym}


def with_octax(n: int, args: argparse.Namespace) -> bool:
    return not args.no_octax and (args.octax_max_envs == 0 or n <= args.octax_max_envs)


def _prepare_sides(rom: Path, n: int, args: argparse.Namespace, progress: Progress) -> dict[str, Prepared]:
    """Ours (named after the mode; gym-<backend>) and, unless skipped, octax, compiled."""
    label = f"gym-{args.backend}" if args.mode == "gym" else args.mode
    progress.stage(f"n={n} {label}: compile")
    sides = {label: PREPARE[args.mode](rom, n, args)}
    progress.advance()
    if with_octax(n, args):
        progress.stage(f"n={n} octax: compile")
        sides["octax"] = theirs = octax_side.prepare(rom, n, args)
        progress.advance()
        if theirs.instructions_per_step != sides[label].instructions_per_step:
            progress.print(f"WARNING: octax runs {theirs.instructions_per_step} instructions per step, "
                           f"we run {sides[label].instructions_per_step}: the ratio compares unequal work")
    return sides


def summary(args: argparse.Namespace, n: int, ours: Prepared, theirs: Optional[Prepared], device: str) -> dict:
    """The fields of one `BENCH throughput` line, in order (gym mode adds `backend` last)."""
    sps = n * args.steps / ours.best_s
    octax_sps = n * args.steps / theirs.best_s if theirs else None
    fields = {
        "mode": args.mode, "n": n, "devices": ours.devices, "steps": args.steps,
        "sps": round(sps), "ips": round(sps * ours.instructions_per_step),
        "state_bytes": ours.state_bytes, "compile_s": round(ours.compile_s, 2),
        "octax_sps": round(octax_sps) if theirs else None,
        "octax_compile_s": round(theirs.compile_s, 2) if theirs else None,
        "ratio": round(sps / octax_sps, 2) if theirs else None, "device": device,
    }
    if args.mode == "gym":
        fields["backend"] = args.backend
    return fields


def run(args: argparse.Namespace) -> int:
    """Runs the benchmark for checked `args` (see `check_args`); prints to stdout, returns 0.

    Raises:
        BenchError, romstore.RomNotFoundError, romstore.RomHashError: see the messages.
    """
    set_host_devices(args.devices)  # before anything computes with JAX
    import jax

    rom = find_rom(GAME, args.rom)
    if args.mode != "machine":  # fail before compiling anything
        from octax_core.env.games import get_spec

        our_action(get_spec(GAME).action_keys, args.key)
    print(machine_line(rom), flush=True)
    if args.devices > jax.device_count():
        raise BenchError(f"--devices {args.devices} but jax sees {jax.device_count()} devices")
    if not args.no_octax and (why := octax_side.import_error()) is not None:
        print(f"# octax comparison skipped: cannot import octax ({why}); pip install 'octax-gym[dev]'", flush=True)
        args.no_octax = True
    total = sum((2 if with_octax(n, args) else 1) * (2 + args.repeats) for n in args.envs)
    progress = Progress(total, args.progress)
    try:
        for n in args.envs:
            _bench_one(rom, n, args, jax.default_backend(), progress)
    finally:
        progress.close()
    return 0


def _bench_one(rom: Path, n: int, args: argparse.Namespace, device: str, progress: Progress) -> None:
    sides = _prepare_sides(rom, n, args, progress)
    time_interleaved(sides, args.repeats, progress, f"n={n}")
    load = load_average()
    for name, side in sides.items():
        progress.print(f"{name:7s} n={n}: {n * args.steps / side.best_s:,.0f} env steps/s "
                       f"({side.best_s * 1e3:.1f} ms for {args.steps} steps), compile {side.compile_s:.2f} s, "
                       f"{side.state_bytes} B/env, {side.instructions_per_step} instr/step, "
                       f"devices={side.devices}, load {load:.2f}")
    ours, theirs = next(iter(sides.values())), sides.get("octax")
    fields = summary(args, n, ours, theirs, device)
    progress.print(bench_line("throughput", fields))
    if args.jsonl:
        with args.jsonl.open("a") as f:
            f.write(json.dumps(fields) + "\n")


if __name__ == "__main__":
    sys.exit(main())
