"""A process of the distributed tests (tests/gym_layer/test_distributed.py): joins a run, steps its
lanes of a sharded vector env with actions that depend only on the global env id and the step, and
saves what its lanes saw. Run as `python tests/distributed_worker.py OUT COORDINATOR N RANK`, or
with N = 0 for one process with two CPU devices (XLA_FLAGS set by the caller)."""

import sys

import numpy as np

GAME, NUM_ENVS, STEPS, SEED = "Brix", 4, 40, 5


def actions_for(global_ids, step, num_actions):
    """The same action for global env i at step t in every layout."""
    return ((np.asarray(global_ids) * 7 + step * 3 + (np.asarray(global_ids) * step) % 5) % num_actions).astype(np.int64)


def play(make_env):
    envs = make_env()
    ids = envs.global_env_ids
    obs, info = envs.reset(seed=SEED)
    out = {"ids": ids, "obs": [obs], "reward": [], "terminated": [], "truncated": [], "score": [info["score"]]}
    for t in range(STEPS):
        obs, reward, terminated, truncated, info = envs.step(actions_for(ids, t, envs.single_action_space.n))
        for name, value in (("obs", obs), ("reward", reward), ("terminated", terminated), ("truncated", truncated),
                            ("score", info["score"])):
            out[name].append(value)
    return {k: np.stack(v) if k != "ids" else v for k, v in out.items()}


def main(out, coordinator, num_processes, rank):
    if num_processes:  # else one process (XLA_FLAGS may give it several CPU devices)
        import octax_gym.distributed
        octax_gym.distributed.initialize(coordinator, num_processes, rank, timeout_s=60)
    import gymnasium as gym
    import octax_gym
    gym.register_envs(octax_gym)
    import jax
    from octax_gym.step.backends import resolve_device
    local = jax.local_devices()
    # a device named as JAX prints it ("cpu:2048" on process 1) or by its place here ("cpu") is this process's
    named = [resolve_device(f"{d.platform}:{d.id}") == d for d in local] + [resolve_device("cpu") == local[0]]
    np.savez(out, names_resolve=np.array(named),
             **play(lambda: gym.make_vec(f"octax/{GAME}-v0", num_envs=NUM_ENVS, devices="all")))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
