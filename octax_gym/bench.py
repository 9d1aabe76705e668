"""Throughput on Pong, ours against the `octax` package: `octax-gym bench` and benchmarks/throughput.py.

The workload is the one of the octax paper: Pong, a constant action, N envs, 100 env steps of
4 frames x 11 instructions, best of several timed runs, compile time excluded. Each N prints
free-form lines, then exactly one summary line starting with ``BENCH throughput``. Modes:

    machine   `Machine.run_frames` alone, scanned in one jitted call
    env       the functional env (`octax_core.make("Pong")`): observation, reward, key splits
    gym       the Gymnasium vector env (`gym.make_vec("octax/Pong-v0", ...)`): one Python call
              per step, actions checked and outputs converted to the `--backend` arrays

`--devices D` splits the batch over D XLA host devices. XLA fixes the device count when JAX runs
its first computation, not when JAX is imported, so the order that matters is "set, then
compute", not "set, then import": `octax-gym` imports JAX with the `octax_gym` package before it
parses anything, yet computes nothing until `run`, whose first act is `set_host_devices` (JAX's
own `jax_num_cpu_devices` option; JAX refuses it once something has run, and `run` then says so).
This module imports JAX only inside functions. Its options live in `cli_bench`, shared by the
command and the script. See benchmarks/README.md for the output fields.
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
from typing import Callable, Optional

from octax_gym.cli_bench import DEFAULT_ROM_DIR, add_arguments, check_args

REPO_ROOT = Path(__file__).resolve().parent.parent
GAME = "Pong"
FRAMES_PER_STEP = 4
INSTRUCTIONS_PER_FRAME = 11
QUIRKS = "chip8"


class BenchError(ValueError):
    """An option this run cannot honour (device count, held key); reported with exit status 1."""


def main(argv: Optional[list[str]] = None) -> int:
    """benchmarks/throughput.py: parses `argv` (the options of `octax-gym bench`, bar off), runs,
    returns the exit status."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_arguments(p)
    args = check_args(p, p.parse_args(argv))
    from octax_core import romstore  # imports JAX, which is fine: nothing has been computed yet

    try:
        return run(args)
    except (BenchError, romstore.RomNotFoundError, romstore.RomHashError) as exc:
        print(f"{p.prog}: error: {exc}", file=sys.stderr)
        return 1


def set_host_devices(n: int) -> None:
    """Asks XLA for n CPU devices; works until JAX's first computation in this process.

    Raises:
        BenchError: JAX has already computed something with another device count.
    """
    if n == 1:
        return
    import jax

    try:
        jax.config.update("jax_num_cpu_devices", n)
    except AttributeError:  # a JAX without the option: its CPU backend reads the flag when it starts
        flag = f"--xla_force_host_platform_device_count={n}"
        os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + flag).strip()
    except RuntimeError as exc:
        raise BenchError(f"--devices {n}: JAX has already run a computation in this process, which fixed "
                         f"its device count; start a new process") from exc


def find_rom(explicit: Optional[Path]) -> Path:
    """The verified Pong ROM: `explicit`, else the ROM store, else DEFAULT_ROM_DIR from the repository root."""
    from octax_core import romstore
    from octax_core.games import get_spec

    spec = get_spec(GAME)
    if explicit is not None:
        return romstore.find_rom(spec, explicit)
    try:
        return romstore.find_rom(spec)
    except romstore.RomNotFoundError:
        beside_repo = REPO_ROOT / os.environ.get("OCTAX_ROM_DIR", DEFAULT_ROM_DIR)
        if not (beside_repo / spec.rom_file).is_file():
            raise
        return romstore.find_rom(spec, beside_repo)


@dataclasses.dataclass
class Prepared:
    """One side of the comparison, compiled and ready to time."""

    run: Callable[[], object]  # one whole rollout; the caller blocks on the result
    compile_s: float           # lower + compile of the whole rollout (gym: first reset + step)
    state_bytes: int           # bytes of one env's state
    instructions_per_step: int
    devices: int               # devices the batch was actually split over
    setup: Callable[[], None] = lambda: None  # run, untimed, before each timed run
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

    env, params = octax_core.make(GAME, rom=rom, frames_per_step=FRAMES_PER_STEP,
                                  instructions_per_frame=INSTRUCTIONS_PER_FRAME)
    keys = jax.random.split(jax.random.key(0), n)
    obs, states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
    actions = jnp.full((n,), _our_action(env.spec.action_keys, args.key), dtype=jnp.int32)
    step = jax.vmap(env.step, in_axes=(0, 0, 0, None))

    def rollout(carry, actions):
        def body(carry, _):
            keys, states, _ = carry
            keys, step_keys = jnp.split(jax.vmap(jax.random.split)(keys), 2, axis=1)
            obs, states, *_ = step(step_keys[:, 0], states, actions, params)
            return (keys[:, 0], states, obs), None
        carry, _ = jax.lax.scan(body, carry, length=args.steps)
        return carry

    run, compile_s, devices = _compile_rollout(rollout, (keys, states, obs), actions, args.devices)
    return Prepared(run, compile_s, _state_bytes(states), FRAMES_PER_STEP * INSTRUCTIONS_PER_FRAME, devices)


def prepare_gym(rom: Path, n: int, args: argparse.Namespace) -> Prepared:
    """The Gymnasium vector env: `steps` calls of `envs.step(actions)`, from Python.

    Each call checks the actions on the host, runs one jitted step (key split, batched step,
    autoreset) and hands obs, reward, flags and info over as `--backend` arrays, as an RL loop
    sees them. The actions are a fixed array of that backend. Every timed run starts from
    `reset(seed=0)` (untimed), so all runs do the same work.
    """
    import gymnasium as gym
    import jax
    import numpy as np

    from octax_gym.registration import env_id

    envs = gym.make_vec(env_id(GAME), num_envs=n, backend=args.backend, rom=rom,
                        frames_per_step=FRAMES_PER_STEP, instructions_per_frame=INSTRUCTIONS_PER_FRAME)
    core = envs.unwrapped.core_env
    actions = np.full((n,), _our_action(core.spec.action_keys, args.key), np.int32)
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
    return Prepared(run, compile_s, _state_bytes(envs.unwrapped.state),
                    config.frames_per_step * config.instructions_per_frame, 1,
                    setup=lambda: envs.reset(seed=0))


def _our_action(action_keys: tuple[int, ...], key: int) -> int:
    """The action holding CHIP-8 `key` (0 = none), or BenchError when the game has no such action."""
    if key < 0:
        return 0
    if key not in action_keys:
        raise BenchError(f"{GAME} has no action for key {key} (keys {list(action_keys)}); use --key -1 or one of them")
    return list(action_keys).index(key) + 1


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


def octax_import_error() -> Optional[str]:
    """None when the `octax` package imports, else why not (it is the `dev` extra)."""
    try:
        import octax  # noqa: F401
    except ImportError as exc:
        return str(exc) or type(exc).__name__
    return None


def prepare_octax(rom: Path, n: int, args: argparse.Namespace) -> Prepared:
    """octax: vmapped `OctaxEnv.step(state, action)`, scanned `steps` times (its paper's benchmark)."""
    import warnings

    import jax
    import jax.numpy as jnp

    # octax's scatters mix dtypes (int32 into bool, uint16 into uint8); JAX warns on every trace.
    warnings.filterwarnings("ignore", message="scatter inputs have incompatible types", category=FutureWarning)
    env = _octax_pong(rom)
    states, obs, _ = jax.vmap(env.reset)(jax.random.split(jax.random.key(0), n))
    keys = [int(k) for k in env.action_set]
    if args.key < 0:
        action = env.num_actions - 1  # octax's no-op is the last action
    elif args.key in keys:
        action = keys.index(args.key)
    else:
        raise BenchError(f"octax Pong has no action for key {args.key} (keys {keys}); "
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


PREPARE = {"machine": prepare_machine, "env": prepare_env, "gym": prepare_gym}


class _Progress:
    """A tqdm bar on stderr over compiles, warm-ups and timed runs; lines printed through it go
    to stdout without tearing the bar. Off: plain prints."""

    def __init__(self, total: int, enabled: bool):
        self._bar = None
        if enabled:
            from tqdm import tqdm

            self._bar = tqdm(total=total, file=sys.stderr, unit="run", dynamic_ncols=True, leave=False)

    def stage(self, text: str) -> None:
        if self._bar is not None:
            self._bar.set_description_str(text)

    def advance(self) -> None:
        if self._bar is not None:
            self._bar.update(1)

    def print(self, line: str) -> None:
        if self._bar is None:
            print(line, flush=True)
        else:
            self._bar.write(line, file=sys.stdout)
            sys.stdout.flush()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


def _time_interleaved(sides: dict[str, Prepared], repeats: int, progress: _Progress, n: int) -> None:
    """Best wall time of each side over `repeats` runs, alternating sides so both see the same load."""
    import jax

    for name, side in sides.items():
        progress.stage(f"n={n} {name}: warm-up")
        side.setup()
        jax.block_until_ready(side.run())  # the first run allocates buffers
        progress.advance()
    for i in range(repeats):
        for name, side in sides.items():
            progress.stage(f"n={n} {name}: run {i + 1}/{repeats}")
            side.setup()
            t0 = time.perf_counter()
            jax.block_until_ready(side.run())
            side.best_s = min(side.best_s, time.perf_counter() - t0)
            progress.advance()


def _with_octax(n: int, args: argparse.Namespace) -> bool:
    return not args.no_octax and (args.octax_max_envs == 0 or n <= args.octax_max_envs)


def _prepare_sides(rom: Path, n: int, args: argparse.Namespace, progress: _Progress) -> dict[str, Prepared]:
    """Ours (named after the mode; gym-<backend>) and, unless skipped, octax, compiled."""
    label = f"gym-{args.backend}" if args.mode == "gym" else args.mode
    progress.stage(f"n={n} {label}: compile")
    sides = {label: PREPARE[args.mode](rom, n, args)}
    progress.advance()
    if _with_octax(n, args):
        progress.stage(f"n={n} octax: compile")
        sides["octax"] = theirs = prepare_octax(rom, n, args)
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


def bench_line(fields: dict) -> str:
    return "BENCH throughput " + " ".join(f"{k}={'na' if v is None else v}" for k, v in fields.items())


def run(args: argparse.Namespace) -> int:
    """Runs the benchmark for checked `args` (see `check_args`); prints to stdout, returns 0.

    Raises:
        BenchError, romstore.RomNotFoundError, romstore.RomHashError: see the messages.
    """
    set_host_devices(args.devices)  # before anything computes with JAX
    import jax

    rom = find_rom(args.rom)
    if args.mode != "machine":  # fail before compiling anything
        from octax_core.games import get_spec

        _our_action(get_spec(GAME).action_keys, args.key)
    device = jax.default_backend()
    print(f"# jax {jax.__version__} backend={device} devices={jax.device_count()} "
          f"python {platform.python_version()} cpus={os.cpu_count()} rom={rom.name}", flush=True)
    if args.devices > jax.device_count():
        raise BenchError(f"--devices {args.devices} but jax sees {jax.device_count()} devices")
    if not args.no_octax and (why := octax_import_error()) is not None:
        print(f"# octax comparison skipped: cannot import octax ({why}); pip install 'octax-gym[dev]'", flush=True)
        args.no_octax = True
    total = sum((2 if _with_octax(n, args) else 1) * (2 + args.repeats) for n in args.envs)
    progress = _Progress(total, args.progress)
    try:
        for n in args.envs:
            _bench_one(rom, n, args, device, progress)
    finally:
        progress.close()
    return 0


def _bench_one(rom: Path, n: int, args: argparse.Namespace, device: str, progress: _Progress) -> None:
    sides = _prepare_sides(rom, n, args, progress)
    _time_interleaved(sides, args.repeats, progress, n)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    for name, side in sides.items():
        progress.print(f"{name:7s} n={n}: {n * args.steps / side.best_s:,.0f} env steps/s "
                       f"({side.best_s * 1e3:.1f} ms for {args.steps} steps), compile {side.compile_s:.2f} s, "
                       f"{side.state_bytes} B/env, {side.instructions_per_step} instr/step, "
                       f"devices={side.devices}, load {load:.2f}")
    ours, theirs = next(iter(sides.values())), sides.get("octax")
    fields = summary(args, n, ours, theirs, device)
    progress.print(bench_line(fields))
    if args.jsonl:
        with args.jsonl.open("a") as f:
            f.write(json.dumps(fields) + "\n")
