"""Offline datasets: collection speed, bytes per step before and after compact storage, load and
sampling speed.

1. Collects `--steps` steps of `--game` (uniform random actions, `--envs` lanes) with
   `octax_gym.datasets.collect_dataset`: the compact storage (HDF5 scale-offset + deflate on the
   observations), then the same seed again with `compress=False` (plain arrays through the same
   writer). Both are compared byte for byte.
2. Writes the same episodes with Minari's own writer (`minari.create_dataset_from_buffers`, the
   way octax-gym stored datasets before the compact storage): the "before" of bytes per step.
3. Loads each dataset: `minari`'s `iterate_episodes` (every episode as Minari gives it) and
   `octax_gym.datasets.load_transitions` (flat arrays), in steps/s.
4. Samples minibatches of 256 (obs, action, reward, next obs, flags) from the loaded transitions:
   numpy on the host, and a jitted `lax.scan` of JAX samples, in transitions/s.

Prints one ``BENCH datasets`` line. The octax package has no dataset collection or loader, so there
is nothing of its to run on the same work.

    python benchmarks/datasets.py                     # Brix, 100,000 steps, 64 lanes
    python benchmarks/datasets.py --game Snake --steps 20000
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Optional

from harness import bench_line, load_average

BATCH = 256


def folder_bytes(path: Path) -> int:
    return sum(f.stat().st_size for f in Path(path).rglob("*") if f.is_file())


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--game", default="Brix")
    parser.add_argument("--steps", type=int, default=100_000, help="steps collected (default 100,000)")
    parser.add_argument("--envs", type=int, default=64, help="lanes (default 64)")
    parser.add_argument("--samples", type=int, default=2000, help="minibatches sampled per side (default 2000)")
    args = parser.parse_args(argv)
    if min(args.steps, args.envs, args.samples) < 1:
        parser.error("--steps, --envs and --samples must be >= 1")
    with tempfile.TemporaryDirectory(prefix="octax-bench-datasets-") as folder:
        os.environ["MINARI_DATASETS_PATH"] = folder
        return run(args)


def run(args) -> int:
    import jax
    import minari
    import numpy as np

    from octax_gym.datasets import collect_dataset, load_transitions

    print(f"# jax {jax.__version__} backend={jax.default_backend()} cpus={os.cpu_count()} game={args.game} "
          f"steps={args.steps} envs={args.envs} load={load_average():.2f}")
    collect_dataset(args.game, "bench/warmup-v0", args.envs, num_envs=args.envs, progress=False)  # the compile
    compact = collect_dataset(args.game, "bench/compact-v0", args.steps, num_envs=args.envs, progress=False)
    plain = collect_dataset(args.game, "bench/plain-v0", args.steps, num_envs=args.envs, progress=False,
                            compress=False)
    sizes = {"compact": folder_bytes(compact.path), "plain": folder_bytes(plain.path)}
    print(f"collect compact: {compact.steps_per_second:,.0f} steps/s, {sizes['compact'] / compact.steps:,.1f} bytes/step")
    print(f"collect plain:   {plain.steps_per_second:,.0f} steps/s, {sizes['plain'] / plain.steps:,.1f} bytes/step")

    episodes = list(compact.dataset.iterate_episodes())
    same = all(np.array_equal(a.observations, b.observations) and np.array_equal(a.actions, b.actions)
               for a, b in zip(episodes, plain.dataset.iterate_episodes()))
    print(f"compact and plain datasets equal: {same}")

    from minari.data_collector import EpisodeBuffer

    buffers = [EpisodeBuffer(id=e.id, seed=0, observations=e.observations, actions=e.actions, rewards=e.rewards,
                             terminations=e.terminations, truncations=e.truncations, infos=e.infos) for e in episodes]
    del episodes
    start = time.perf_counter()
    minari_dataset = minari.create_dataset_from_buffers(
        "bench/minari-v0", buffers, env=compact.dataset.spec.env_spec, algorithm_name="random",
        observation_space=compact.dataset.observation_space, action_space=compact.dataset.action_space,
        jpeg_encoding=False, author="bench", author_email="-", code_permalink="-")
    minari_write_s = time.perf_counter() - start
    del buffers
    sizes["minari"] = folder_bytes(Path(minari_dataset.storage.data_path).parent)
    print(f"Minari's writer:  {args.steps / minari_write_s:,.0f} steps/s written, "
          f"{sizes['minari'] / args.steps:,.1f} bytes/step")

    def load_speed(dataset_id: str) -> tuple[float, float]:
        dataset = minari.load_dataset(dataset_id)
        start = time.perf_counter()
        steps = sum(len(e) for e in dataset.iterate_episodes())
        iterate = steps / (time.perf_counter() - start)
        start = time.perf_counter()
        data = load_transitions(dataset)
        flat = len(data) / (time.perf_counter() - start)
        return iterate, flat, data

    loads = {}
    for name in ("minari", "plain", "compact"):
        iterate, flat, data = load_speed(f"bench/{name}-v0")
        loads[name] = (iterate, flat)
        print(f"load {name:8s}: iterate_episodes {iterate:,.0f} steps/s, load_transitions {flat:,.0f} steps/s")

    rng = np.random.default_rng(0)
    start = time.perf_counter()
    for _ in range(args.samples):
        data.sample(rng, BATCH)
    numpy_tps = args.samples * BATCH / (time.perf_counter() - start)

    on_device = data.device_put()

    @jax.jit
    def draw(data, key):
        def body(total, key):
            batch = data.sample(key, BATCH)
            return total + batch.obs.sum(dtype=np.int32) + batch.next_obs.sum(dtype=np.int32), None
        return jax.lax.scan(body, np.int32(0), jax.random.split(key, args.samples))[0]

    jax.block_until_ready(draw(on_device, jax.random.key(0)))
    start = time.perf_counter()
    jax.block_until_ready(draw(on_device, jax.random.key(1)))
    jax_tps = args.samples * BATCH / (time.perf_counter() - start)
    print(f"sample {BATCH}: numpy {numpy_tps:,.0f} transitions/s, jax (jit, scan) {jax_tps:,.0f} transitions/s")

    print(bench_line("datasets", {
        "game": args.game, "steps": args.steps, "envs": args.envs, "equal": same,
        "collect_sps": round(compact.steps_per_second), "collect_plain_sps": round(plain.steps_per_second),
        "bytes_per_step": round(sizes["compact"] / args.steps, 1),
        "bytes_per_step_plain": round(sizes["plain"] / args.steps, 1),
        "bytes_per_step_minari": round(sizes["minari"] / args.steps, 1),
        "ratio_vs_minari": round(sizes["minari"] / sizes["compact"], 1),
        "load_sps": round(loads["compact"][1]), "load_sps_plain": round(loads["plain"][1]),
        "iterate_sps": round(loads["compact"][0]), "iterate_sps_minari": round(loads["minari"][0]),
        "sample_tps_numpy": round(numpy_tps), "sample_tps_jax": round(jax_tps),
        "load": f"{load_average():.2f}"}))
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
