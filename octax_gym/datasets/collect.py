"""Offline datasets: play a game in many lanes at once and store every episode as a Minari dataset.

    from octax_gym.datasets import collect_dataset, episode_seed
    result = collect_dataset("Brix", "octax/Brix-random-v0", num_steps=100_000, num_envs=64)
    dataset = result.dataset                       # the same as minari.load_dataset("octax/Brix-random-v0")

Minari's own `DataCollector` wraps one env and steps it alone. Here all `num_envs` lanes step in
one jitted call, the compiled env step behind `OctaxEnv` and `OctaxVectorEnv`
(`octax_gym.step.compiled_step`), and each lane's episode is gathered on the host until it ends. A lane
whose episode ends is reset in the same call with the next unused seed, so every episode, not
just each lane's first, starts the way `OctaxEnv.reset(seed=s)` starts: from the key chain of
its own seed s. `dataset.recover_environment()`, reset with an episode's seed (`episode_seed`)
and stepped with its actions, gives back its observations, rewards and flags bit for bit. See
docs/datasets.md.

Minari is the optional `datasets` extra: it is imported inside the functions here, so
`import octax_gym` works without it.
"""

from __future__ import annotations

import dataclasses
import functools
import shutil
import time
from pathlib import Path
from typing import Any, Optional

import gymnasium
import jax
import jax.numpy as jnp
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode
from tqdm import tqdm

from octax_core.validate import check_int
from octax_gym.datasets.diskwrite import DatasetWriteError
from octax_gym.datasets.storage import (DatasetWriter, EpisodeRecord, check_dataset_id, import_minari,
                                        kept_episodes)
from octax_gym.envs.choices import check_names
from octax_gym.envs.game_names import resolve_env_id
from octax_gym.policies import Act, Policy, check_policy, make_policy, policy_name
from octax_gym.step import action_check, compiled_step
from octax_gym.step.compiled_step import GYM_ENV_OPTIONS, MAX_SEED

# Finished episodes are written once they hold this many steps: ~160 MB of 32 x 64 frames (CHIP-8),
# 4x that of 64 x 128 ones (SUPER-CHIP, XO-CHIP).
FLUSH_STEPS = 20_000


@dataclasses.dataclass(frozen=True)
class CollectResult:
    """What `collect_dataset` made: the dataset, and how long collecting and writing it took."""

    dataset: Any  # minari.MinariDataset
    dataset_id: str
    path: Path  # the dataset's folder (its data/ holds main_data.hdf5 and metadata.json)
    episodes: int
    steps: int
    seconds: float  # wall time of stepping, policy and writing, the first steps' JAX compile included

    @property
    def steps_per_second(self) -> float:
        return self.steps / self.seconds if self.seconds > 0 else float("inf")


def collect_dataset(env_id: str, dataset_id: str, num_steps: int, *, num_envs: int = 64,
                    policy: Policy = None, seed: int = 0, overwrite: bool = False, progress: bool = True,
                    author: Optional[str] = None, author_email: Optional[str] = None,
                    code_permalink: Optional[str] = None, description: Optional[str] = None,
                    algorithm_name: Optional[str] = None, flush_steps: int = FLUSH_STEPS, compress: bool = True,
                    extra_metadata: Optional[dict[str, Any]] = None, **env_options) -> CollectResult:
    """Plays `num_steps` env steps in `num_envs` lanes at once and writes them as a Minari dataset.

    Episodes end where the env ends them (terminated, or truncated at max_episode_steps); the
    episodes still running when `num_steps` is reached are stored cut there, truncated=True at
    their last step. Each episode stores T + 1 observations (uint8, exact: no JPEG), T actions,
    rewards, terminations, truncations, and T + 1 infos (score, lives, episode_step; the first
    from the reset), and its reset seed (`episode_seed`). The lanes' first episodes get seeds
    seed .. seed + num_envs - 1, then every new episode the next unused seed. The same
    arguments give the same dataset.

    Args:
        env_id: a game id ("Brix") or its Gymnasium id ("octax/Brix-v0"), in any case.
        dataset_id: Minari's `namespace/name-vN` (namespace optional; letters, digits, '-', '_';
            the version -vN is required), written under MINARI_DATASETS_PATH (default
            ~/.minari/datasets).
        num_steps: transitions to store in all, >= 1 (the last batched step may fill only some lanes).
        num_envs: lanes stepped together, >= 1.
        policy: None or "random" (uniform actions drawn from `seed`), "noop" (action 0)
            (`octax_gym.policies.POLICIES`), or a function from the batched observation, numpy
            uint8 (num_envs, frames_per_step, H, W), to one action per lane (ints in 0..n-1,
            shape (num_envs,)), e.g. a trained agent.
        seed: the first episode seed, 0 <= seed and seed + num_envs + num_steps <= 2**32.
        overwrite: replace a dataset of that id; otherwise an existing one is an error.
        progress: a tqdm progress bar on stderr.
        author, author_email, code_permalink, description, algorithm_name: Minari's metadata (the
            description defaults to one naming the game, policy, lanes and seed; algorithm_name to
            the policy's name).
        flush_steps: finished episodes are written in groups of at least this many steps, which
            bounds the memory they hold.
        compress: store the observations through HDF5's scale-offset and deflate filters (about
            70x smaller; read back bit for bit by any HDF5 reader, `minari.load_dataset` included:
            `octax_gym.datasets.storage`); False stores them plain.
        extra_metadata: more keys for the dataset's metadata.json (JSON values), e.g. a policy card.
        **env_options: the env's options (`octax_gym.step.compiled_step.GYM_ENV_OPTIONS`: max_episode_steps,
            frames_per_step, noop_max, repeat_action_probability, ...); they are stored in the
            dataset's env spec, so `recover_environment()` builds the same env.

    Returns:
        A `CollectResult`: the `minari.MinariDataset`, its id and folder, episodes, steps, seconds.

    Raises:
        UnknownOptionError: an unknown game, env option or policy name; the message names the
            valid choices.
        ValueError: a malformed or existing dataset id, bad num_steps, num_envs or seed, or a
            policy returning a wrong shape of actions (`InvalidActionError`, a ValueError, for
            one out of range).
        TypeError: a policy returning actions that are not integers.
        ImportError: Minari (the `datasets` extra) is not installed.
        DatasetWriteError: an OSError: a write failed (a full disk, a file-size limit). The
            episodes of the groups written before stay, a dataset as a kill leaves it; the
            message says how many and how to make them one file. Any other error removes the
            dataset's folder.
    """
    minari = import_minari()
    gym_id = resolve_env_id(env_id)
    check_int("num_steps", num_steps)
    check_int("num_envs", num_envs)
    check_int("seed", seed, minimum=0, maximum=MAX_SEED - num_envs - num_steps)
    check_int("flush_steps", flush_steps)
    check_dataset_id(dataset_id)
    check_names("env option(s)", env_options, GYM_ENV_OPTIONS)
    check_policy(policy)
    path = minari.storage.get_dataset_path(dataset_id)
    if path.exists() and not overwrite:
        raise ValueError(f"dataset {dataset_id!r} already exists at {path}; pass overwrite=True "
                         "(--overwrite) to replace it, or pick another name or version")
    lanes = _Lanes(gymnasium.spec(gym_id).kwargs["game"], num_envs, env_options)  # checks the options' values
    act = make_policy(policy, num_envs, lanes.num_actions, seed)
    metadata = {"algorithm_name": algorithm_name or policy_name(policy), "author": author, "author_email": author_email,
                "code_permalink": code_permalink,
                "description": description or (f"{gym_id}, {policy_name(policy)} policy, {num_steps} steps from "
                                               f"{num_envs} lanes, episode seeds from {seed}: collected by "
                                               "octax_gym.datasets.collect_dataset")}
    if path.exists():
        shutil.rmtree(path)
    try:
        start = time.perf_counter()
        writer = DatasetWriter(dataset_id, recovery_spec(gym_id, env_options), lanes.observation_space,
                               spaces.Discrete(lanes.num_actions), flush_steps, metadata,
                               extra_metadata=extra_metadata, compress=compress)
        with tqdm(total=num_steps, desc=f"collecting {gym_id}", unit="step", disable=not progress) as bar:
            _collect(lanes, act, num_steps, seed, writer, bar)
        dataset = writer.close()
        seconds = time.perf_counter() - start
    except DatasetWriteError as exc:  # a full disk: the episodes written are kept, as a kill keeps them
        if kept_episodes(path)[0] == 0:
            shutil.rmtree(path, ignore_errors=True)
            raise exc.with_outcome("no episode had been written; nothing is kept") from exc
        raise
    except BaseException:
        shutil.rmtree(path, ignore_errors=True)  # no half-written dataset left behind
        raise
    return CollectResult(dataset=dataset, dataset_id=dataset_id, path=Path(path), episodes=writer.episodes,
                         steps=writer.steps, seconds=seconds)


def recovery_spec(gym_id: str, env_options: dict) -> gymnasium.envs.registration.EnvSpec:
    """The registered spec with the env options in its kwargs, so `gymnasium.make(spec)` (and
    Minari's `recover_environment`) builds the env the data came from.

    A `max_episode_steps` option goes into the kwargs, the env's own truncation (what `make_vec`
    builds with too), and into the spec's field, which `env.spec.max_episode_steps` shows and
    whose `TimeLimit` ends episodes at the same step (`octax_gym.envs.registration`).
    """
    spec = gymnasium.spec(gym_id)
    kwargs = {**spec.kwargs, **env_options}
    bound = kwargs.get("max_episode_steps")
    return dataclasses.replace(spec, kwargs=kwargs, max_episode_steps=spec.max_episode_steps if bound is None else bound)


def episode_seed(dataset, episode_id: int) -> int:
    """The seed of one stored episode: `env.reset(seed=episode_seed(dataset, i))` on the
    recovered env starts episode i, and its actions then replay it exactly."""
    (metadata,) = dataset.storage.get_episode_metadata([episode_id])
    if metadata.get("seed") is None:
        raise ValueError(f"episode {episode_id} of {dataset.id!r} has no stored seed")
    return int(metadata["seed"])


# --- the collection loop ---------------------------------------------------------------------


def _collect(lanes: "_Lanes", act: Act, num_steps: int, seed: int,
             writer: DatasetWriter, bar: tqdm) -> None:
    """Steps every lane at once until `num_steps` transitions are stored, starting a new episode
    in a lane, with the next unused seed, as soon as its episode ends."""
    num_envs = lanes.num_envs
    obs, info = lanes.start(seed)  # lane i: seed + i
    episodes = [EpisodeRecord(seed + lane, obs[lane], _row(info, lane)) for lane in range(num_envs)]
    next_seed = seed + num_envs
    left = num_steps
    while left > 0:
        actions = action_check.check_batch(act(obs), num_envs, lanes.num_actions, lanes.game, "from the policy")
        last, reward, terminated, truncated, info, obs, first_info, seeds = lanes.step(actions, next_seed)
        used = min(num_envs, left)  # the last batched step may fill only the first lanes
        for lane in range(used):
            episodes[lane].add(int(actions[lane]), last[lane], float(reward[lane]), bool(terminated[lane]),
                               bool(truncated[lane]), _row(info, lane))
        left -= used
        bar.update(used)
        for lane in np.flatnonzero(terminated | truncated):
            next_seed += 1
            if lane < used:
                writer.add(episodes[lane], cut=False)
                episodes[lane] = EpisodeRecord(int(seeds[lane]), obs[lane], _row(first_info, lane))
    for episode in episodes:
        if len(episode) and not episode.ended:
            writer.add(episode, cut=True)


class _Lanes:
    """`num_envs` lanes of one game driven by the compiled env step behind `OctaxEnv` and
    `OctaxVectorEnv` (`octax_gym.step.compiled_step`), with the envs' key derivation, in one jitted
    call per step: the batched step, then a reset of each lane whose episode just ended.

    Seeds flow as in the envs: a lane reset with seed s starts its key chain at
    `jax.random.key(s)` and resets with the key's first split, exactly as `OctaxEnv.reset(seed=s)`
    (or a vector env's masked `reset`) does, and every step splits the lane's key alone. The
    lanes ending in a step take the seeds next_seed, next_seed + 1, ... in lane order.
    """

    def __init__(self, game: str, num_envs: int, env_options: dict):
        self.compiled, self.params = compiled_step.build(game, None, env_options)
        core = self.compiled.env
        self.num_envs, self.game, self.num_actions = num_envs, core.spec.id, core.num_actions
        self.observation_space = spaces.Box(0, core.observation_high, core.observation_shape, np.uint8)
        self._step = _step_and_reset(self.compiled)
        self._keys = self._state = None

    def start(self, seed: int) -> tuple[np.ndarray, dict]:
        """Resets lane i with seed + i; returns the observations and infos (numpy)."""
        keys = compiled_step.keys_from_seeds(compiled_step.seeds_for(seed, self.num_envs))
        self._keys, obs, self._state, info = self.compiled.reset(keys, None, None, None, self.params)
        return jax.device_get((obs, _unmasked(info)))

    def step(self, actions: np.ndarray, next_seed: int):
        """Returns (as numpy) each lane's observation, reward, terminated, truncated and info
        after the step, then the observation and info each lane goes on from (a new episode's
        first where one ended), and the seed of each new episode (where one ended)."""
        self._keys, self._state, outputs = self._step(
            self._keys, self._state, jnp.asarray(actions, jnp.int32), jnp.uint32(next_seed), self.params)
        return jax.device_get(outputs)


@functools.lru_cache(maxsize=16)
def _step_and_reset(compiled: compiled_step.CompiledStep):
    """The lanes' jitted step for one game and config (cached, like the compiled step: one compile per
    batch size)."""
    def step_and_reset(keys, state, actions, next_seed, params):
        keys, last, state, reward, terminated, truncated, info, _ = compiled.step_fns[AutoresetMode.DISABLED](
            keys, state, actions, jnp.asarray(action_check.NO_REPORT, jnp.int32), params)
        ended = terminated | truncated
        seeds = next_seed + jnp.cumsum(ended, dtype=jnp.uint32) - 1  # lane order
        keys = compiled_step.select_keys(ended, compiled_step.keys_from_seeds(seeds), keys)
        keys, obs, state, first_info = compiled.reset_fn(keys, state, last, ended, params)
        return keys, state, (last, reward, terminated, truncated, _unmasked(info), obs, _unmasked(first_info),
                             seeds)

    return jax.jit(step_and_reset, donate_argnums=(1,), compiler_options=compiled.compiler_options)


def _unmasked(info: dict) -> dict:
    """The info (score, lives, episode_step) without Gymnasium's `_name` masks."""
    return {name: value for name, value in info.items() if not name.startswith("_")}


def _row(info: dict, lane: int) -> dict[str, Any]:
    """One lane's info."""
    return {name: value[lane] for name, value in info.items()}
