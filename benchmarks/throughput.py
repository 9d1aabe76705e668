"""Throughput of the CHIP-8 core on Pong, and of the `octax` package on the same work.

The workload is the one of the octax paper: Pong, a constant action, N machines, 100 env steps of
4 frames x 11 instructions, best of several timed runs, compile time excluded. Each N prints
free-form lines, then exactly one summary line starting with ``BENCH throughput``.

    python benchmarks/throughput.py                    # N = 1, 64, 512, 2048, 8192, with octax
    python benchmarks/throughput.py --quick            # N = 64, 512, 2 repeats (smoke test)
    python benchmarks/throughput.py --envs 512 --devices 2 --no-octax
    python benchmarks/throughput.py --mode env         # the functional env API: obs and reward too

See benchmarks/README.md for what each field means.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import sys
import time
from pathlib import Path
from typing import Callable

REPO_ROOT = Path(__file__).resolve().parent.parent
DEFAULT_ROM_DIR = "../shared/roms/octax"
ROM_NAME = "Pong (1 player).ch8"
FRAMES_PER_STEP = 4
INSTRUCTIONS_PER_FRAME = 11
QUIRKS = "chip8"


def _parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--envs", default="1,64,512,2048,8192", help="comma-separated batch sizes N")
    p.add_argument("--mode", choices=("machine", "env"), default="machine",
                   help="machine: Machine.run_frames alone; env: octax_core.make('Pong') reset + step, "
                        "observation (4 frames, uint8) and reward included (default machine)")
    p.add_argument("--steps", type=int, default=100, help="env steps per timed run (default 100)")
    p.add_argument("--repeats", type=int, default=5, help="timed runs per N; the best is kept (default 5)")
    p.add_argument("--key", type=int, default=1,
                   help="CHIP-8 key held for the whole run, 0..15, or -1 for none (default 1, "
                        "octax Pong's action 0 as in its paper benchmark)")
    p.add_argument("--devices", type=int, default=1,
                   help="split the batch over this many XLA host devices with shard_map (default 1)")
    p.add_argument("--no-octax", action="store_true", help="skip the octax comparison")
    p.add_argument("--octax-max-envs", type=int, default=0,
                   help="run octax only for N up to this (its compile time grows with N; 0 = no cap)")
    p.add_argument("--quick", action="store_true", help="N = 64,512 and 2 repeats (smoke test)")
    p.add_argument("--rom", type=Path, default=None,
                   help=f"Pong ROM path (default: $OCTAX_ROM_DIR/{ROM_NAME}, OCTAX_ROM_DIR defaulting "
                        f"to {DEFAULT_ROM_DIR} beside the repository root)")
    p.add_argument("--jsonl", type=Path, default=None, help="also append one JSON object per N to this file")
    args = p.parse_args(argv)
    if args.quick:
        args.envs, args.repeats = "64,512", 2
    args.envs = [int(n) for n in args.envs.split(",") if n.strip()]
    if not args.envs or min(args.envs) < 1:
        p.error(f"--envs must be positive integers, got {args.envs}")
    if args.steps < 1 or args.repeats < 1 or args.devices < 1:
        p.error("--steps, --repeats and --devices must be >= 1")
    if not -1 <= args.key <= 15:
        p.error(f"--key must be in -1..15, got {args.key}")
    return args


def _set_host_devices(n: int) -> None:
    """Ask XLA for n CPU devices; only takes effect if jax has not been imported yet."""
    if n == 1:
        return
    if "jax" in sys.modules:
        raise RuntimeError("--devices must be handled before jax is imported")
    flag = f"--xla_force_host_platform_device_count={n}"
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + flag).strip()


def _find_rom(explicit: Path | None) -> Path:
    if explicit is not None:
        candidates = [explicit]
    else:
        rom_dir = Path(os.environ.get("OCTAX_ROM_DIR", DEFAULT_ROM_DIR))
        # A relative OCTAX_ROM_DIR is taken from the working directory, then from the repository root.
        candidates = [rom_dir / ROM_NAME] if rom_dir.is_absolute() else [
            Path.cwd() / rom_dir / ROM_NAME, REPO_ROOT / rom_dir / ROM_NAME]
    for path in candidates:
        if path.is_file():
            return path.resolve()
    raise SystemExit(f"Pong ROM not found; looked at {', '.join(map(str, candidates))}. "
                     f"Set OCTAX_ROM_DIR or pass --rom.")


@dataclasses.dataclass
class Prepared:
    """One side of the comparison, compiled and ready to time."""

    run: Callable[[], object]  # one whole rollout; the caller blocks on the result
    compile_s: float           # lower + compile of the whole rollout
    state_bytes: int           # bytes of one env's state
    instructions_per_step: int
    devices: int               # devices the batch was actually split over
    best_s: float = float("inf")


def _state_bytes(batched_state) -> int:
    """Bytes of one env's state: the sum of nbytes over the leaves, batch dimension removed."""
    import jax
    import numpy as np

    total = 0
    for leaf in jax.tree.leaves(batched_state):
        if jax.dtypes.issubdtype(leaf.dtype, jax.dtypes.prng_key):
            leaf = jax.random.key_data(leaf)
        total += int(np.prod(leaf.shape[1:], dtype=np.int64)) * leaf.dtype.itemsize
    return total


def _shard_map(f, **kwargs):
    import jax

    if hasattr(jax, "shard_map"):
        return jax.shard_map(f, check_vma=False, **kwargs)
    from jax.experimental.shard_map import shard_map  # jax < 0.7

    return shard_map(f, check_rep=False, **kwargs)


def _compile_rollout(rollout: Callable, inputs, actions, devices: int):
    """jit (and, for several devices, shard_map over the batch axis) then AOT-compile.

    Returns a no-argument function running the compiled rollout on its inputs (placed where it
    wants them), the compile time and the number of devices used (1 when N does not split evenly).
    """
    import jax
    from jax.sharding import NamedSharding, PartitionSpec as P

    n = actions.shape[0]
    if devices > 1 and n % devices == 0:
        mesh = jax.make_mesh((devices,), ("env",))
        # Each device runs the plain per-env rollout on its slice; nothing crosses devices. The
        # varying-manual-axes check is off because it also rejects loop carries that start as
        # constants inside the code under test (octax's or ours), which is harmless here.
        fn = jax.jit(_shard_map(rollout, mesh=mesh, in_specs=(P("env"), P("env")), out_specs=P("env")))
        inputs, actions = jax.device_put((inputs, actions), NamedSharding(mesh, P("env")))
    else:
        devices, fn = 1, jax.jit(rollout)
    inputs, actions = jax.block_until_ready((inputs, actions))
    t0 = time.perf_counter()
    compiled = fn.lower(inputs, actions).compile()
    return (lambda: compiled(inputs, actions)), time.perf_counter() - t0, devices


def _time_interleaved(sides: list[Prepared], repeats: int) -> None:
    """Best wall time of each side over `repeats` runs, alternating sides so both see the same load."""
    import jax

    for side in sides:
        jax.block_until_ready(side.run())  # warm-up: the first run allocates buffers
    for _ in range(repeats):
        for side in sides:
            t0 = time.perf_counter()
            jax.block_until_ready(side.run())
            side.best_s = min(side.best_s, time.perf_counter() - t0)


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

    run, compile_s, devices = _compile_rollout(rollout, states, actions, args.devices)
    return Prepared(run, compile_s, _state_bytes(states), FRAMES_PER_STEP * INSTRUCTIONS_PER_FRAME, devices)


def prepare_env(rom: Path, n: int, args: argparse.Namespace) -> Prepared:
    """Our functional env: vmapped `env.step(key, state, action, params)`, scanned `steps` times.

    Each step produces the (4, 32, 64) uint8 observation, the reward and the flags, and splits
    its key, as an RL loop does; the observation rides in the carry so none of it is dropped.
    """
    import jax
    import jax.numpy as jnp
    import octax_core

    env, params = octax_core.make("Pong", rom=rom, frames_per_step=FRAMES_PER_STEP,
                                  instructions_per_frame=INSTRUCTIONS_PER_FRAME)
    action = 0 if args.key < 0 else list(env.spec.action_keys).index(args.key) + 1
    keys = jax.random.split(jax.random.key(0), n)
    obs, states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
    actions = jnp.full((n,), action, dtype=jnp.int32)
    step = jax.vmap(env.step, in_axes=(0, 0, 0, None))

    def rollout(carry, actions):
        def body(carry, _):
            keys, states, _ = carry
            keys, step_keys = jnp.split(jax.vmap(jax.random.split)(keys), 2, axis=1)
            obs, states, reward, terminated, truncated, _ = step(step_keys[:, 0], states, actions, params)
            return (keys[:, 0], states, obs), None
        carry, _ = jax.lax.scan(body, carry, length=args.steps)
        return carry

    run, compile_s, devices = _compile_rollout(rollout, (keys, states, obs), actions, args.devices)
    state_bytes = _state_bytes(states)
    return Prepared(run, compile_s, state_bytes, FRAMES_PER_STEP * INSTRUCTIONS_PER_FRAME, devices)


def _octax_pong(rom: Path):
    """The octax Pong env, built as `octax.environments.create_environment("pong")` builds it.

    create_environment looks for ROMs in a `roms/` folder above the installed package, so the
    env is built from the same game module with our ROM path instead.
    """
    from octax.env import OctaxEnv
    from octax.environments import pong

    return OctaxEnv(
        rom_path=str(rom),
        score_fn=pong.score_fn,
        terminated_fn=pong.terminated_fn,
        action_set=pong.action_set,
        startup_instructions=getattr(pong, "startup_instructions", 0),
        custom_startup=getattr(pong, "custom_startup", None),
        disable_delay=getattr(pong, "disable_delay", False),
    )


def prepare_octax(rom: Path, n: int, args: argparse.Namespace) -> Prepared:
    """octax: vmapped `OctaxEnv.step(state, action)`, scanned `steps` times (its paper's benchmark)."""
    import warnings

    import jax
    import jax.numpy as jnp

    # octax's scatters mix dtypes (int32 into bool, uint16 into uint8); JAX warns on every trace.
    warnings.filterwarnings("ignore", message="scatter inputs have incompatible types", category=FutureWarning)
    env = _octax_pong(rom)
    states, obs, _ = jax.vmap(env.reset)(jax.random.split(jax.random.key(0), n))
    if args.key < 0:
        action = env.num_actions - 1  # octax's no-op is the last action
    elif args.key in [int(k) for k in env.action_set]:
        action = [int(k) for k in env.action_set].index(args.key)
    else:
        raise SystemExit(f"octax Pong has no action for key {args.key} (keys {env.action_set.tolist()}); "
                         f"use --key -1, a Pong key, or --no-octax")
    actions = jnp.full((n,), action, dtype=jnp.int32)
    step = jax.vmap(env.step)

    def rollout(carry, actions):
        # The observation rides in the carry so that producing it is part of the measured step,
        # as it is in an RL loop (and in octax's own benchmark, which keeps every step's output).
        def body(carry, _):
            next_state, next_obs, *_ = step(carry[0], actions)
            return (next_state, next_obs), None
        carry, _ = jax.lax.scan(body, carry, length=args.steps)
        return carry

    run, compile_s, devices = _compile_rollout(rollout, (states, obs), actions, args.devices)
    return Prepared(run, compile_s, _state_bytes(states), env.instructions_per_step * env.frame_skip, devices)


def main(argv: list[str] | None = None) -> int:
    args = _parse_args(argv)
    _set_host_devices(args.devices)
    import jax  # only now: XLA_FLAGS must be set first

    rom = _find_rom(args.rom)
    backend = jax.default_backend()
    print(f"# jax {jax.__version__} backend={backend} devices={jax.device_count()} "
          f"python {platform.python_version()} cpus={os.cpu_count()} rom={rom.name}", flush=True)
    if args.devices > jax.device_count():
        raise SystemExit(f"--devices {args.devices} but jax sees {jax.device_count()} devices")

    for n in args.envs:
        ours = (prepare_env if args.mode == "env" else prepare_machine)(rom, n, args)
        theirs = None
        if not args.no_octax and (args.octax_max_envs == 0 or n <= args.octax_max_envs):
            theirs = prepare_octax(rom, n, args)
            if theirs.instructions_per_step != ours.instructions_per_step:
                print(f"WARNING: octax runs {theirs.instructions_per_step} instructions per step, "
                      f"we run {ours.instructions_per_step}: the ratio compares unequal work", flush=True)
        _time_interleaved([ours] + ([theirs] if theirs else []), args.repeats)
        load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
        for name, side in [(args.mode, ours), ("octax", theirs)]:
            if side:
                print(f"{name:7s} n={n}: {n * args.steps / side.best_s:,.0f} env steps/s "
                      f"({side.best_s * 1e3:.1f} ms for {args.steps} steps), compile {side.compile_s:.2f} s, "
                      f"{side.state_bytes} B/env, {side.instructions_per_step} instr/step, "
                      f"devices={side.devices}, load {load:.2f}", flush=True)
        sps = n * args.steps / ours.best_s
        octax_sps = n * args.steps / theirs.best_s if theirs else None
        summary = {
            "mode": args.mode, "n": n, "devices": ours.devices, "steps": args.steps,
            "sps": round(sps), "ips": round(sps * ours.instructions_per_step),
            "state_bytes": ours.state_bytes, "compile_s": round(ours.compile_s, 2),
            "octax_sps": round(octax_sps) if theirs else None,
            "octax_compile_s": round(theirs.compile_s, 2) if theirs else None,
            "ratio": round(sps / octax_sps, 2) if theirs else None, "device": backend,
        }
        print("BENCH throughput " + " ".join(
            f"{k}={'na' if v is None else v}" for k, v in summary.items()), flush=True)
        if args.jsonl:
            with args.jsonl.open("a") as f:
                f.write(json.dumps(summary) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
