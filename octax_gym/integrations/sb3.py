"""Stable-Baselines3 support: a native `VecEnv`, the paper's CNN and its PPO hyperparameters.

    from stable_baselines3 import PPO
    from octax_gym.sb3 import make_sb3_vec_env, ppo_kwargs

    venv = make_sb3_vec_env("Brix", 64)                  # VecMonitor(OctaxSB3VecEnv), obs uint8 (64, 4, 32, 64)
    model = PPO("CnnPolicy", venv, **ppo_kwargs(64))     # or **PPO_KWARGS with 512 envs (the paper's)
    model.learn(100_000)

SB3 takes neither a Gymnasium `VectorEnv` nor 32 x 64 frames in its NatureCNN (its 8 x 8 stride-4
kernel needs 36 pixels a side), so this module gives it both natively. Importing it imports torch
and SB3 (`pip install 'octax-gym[sb3]'`); `import octax_gym` alone does not. See docs/sb3.md.
"""

from __future__ import annotations

import warnings
from typing import Any

import gymnasium
import numpy as np
import torch
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from stable_baselines3.common.vec_env import VecEnv, VecMonitor
from stable_baselines3.common.vec_env.base_vec_env import VecEnvIndices, VecEnvObs, VecEnvStepReturn

from octax_gym.envs.vector import OctaxVectorEnv
from octax_gym.networks import FEATURES, OctaxCNN
from octax_gym.step.compiled_step import MAX_SEED

FIXED_KEYWORDS = ("autoreset_mode", "backend", "obs_scale")  # what SB3's contract decides for us


class OctaxSB3VecEnv(VecEnv):
    """`num_envs` copies of one game as an SB3 `VecEnv`, stepped by one jitted call.

    It wraps an `OctaxVectorEnv` in SAME_STEP autoreset with the numpy backend and `obs_scale=255`.
    Observation: uint8 (num_envs, frames_per_step, 32, 64), lit pixels 255, channel-first, so SB3
    sees an image space and divides by 255 itself. Actions: int array (num_envs,), 0 = no key.

    `step` follows SB3's `DummyVecEnv`: `dones = terminated | truncated`; an env that ends returns
    the next episode's first observation, its `infos[i]` is the ending step's info (score, lives,
    episode_step) plus `terminal_observation` (the last observation, a copy) and
    `TimeLimit.truncated` (truncated and not terminated; False on every other row), and
    `reset_infos[i]` holds the new episode's info. `seed(s)` and `set_options(o)` apply at the next
    `reset()` only: env i gets seed s + i; the one option is `{"reset_mask": m}`, which resets only
    the rows where m (bool, (num_envs,)) is True and returns every row's observation.

    The envs share one batched Gymnasium env (`vector_env`): `get_attr` reads its attribute once
    for each index, `env_method` calls its method once (the result listed per index), and
    `set_attr` sets it for all envs at once.

    Args:
        game: a registered game id ("Brix") or a `GameSpec`.
        num_envs: number of envs.
        **kwargs: the keywords of `OctaxVectorEnv` (docs/gymnasium.md) except autoreset_mode,
            backend and obs_scale, which this adapter fixes.

    Raises:
        TypeError: a fixed or unknown keyword.
    """

    def __init__(self, game: Any, num_envs: int, **kwargs):
        fixed = sorted(set(kwargs) & set(FIXED_KEYWORDS))
        if fixed:
            raise TypeError(f"OctaxSB3VecEnv fixes {fixed} (SB3 needs same-step autoreset, numpy arrays and "
                            "0/255 frames); drop them, or use OctaxVectorEnv for other settings")
        self.vector_env = OctaxVectorEnv(game, num_envs, autoreset_mode=AutoresetMode.SAME_STEP,
                                         backend="numpy", obs_scale=255, **kwargs)
        space = self.vector_env.single_observation_space
        if space.shape[0] >= min(space.shape[1:]):  # SB3 takes the smallest axis for the channels
            raise ValueError(f"frames_per_step must be below 32 for SB3 to see channel-first images, "
                             f"got {space.shape[0]}")
        super().__init__(self.vector_env.num_envs, space, self.vector_env.single_action_space)
        self.metadata = {**self.metadata, "render_fps": self.vector_env.metadata["render_fps"],
                         "autoreset_mode": AutoresetMode.SAME_STEP}
        self._actions: np.ndarray | None = None

    def reset(self) -> VecEnvObs:
        """Resets every env (or the `reset_mask` rows), using and then clearing the stored seeds and options."""
        obs, info = self.vector_env.reset(seed=self._seed_arg(), options=self._options_arg())
        self._reset_seeds()
        self._reset_options()
        self.reset_infos = _split_info(info, self.num_envs)
        # A copy: the numpy backend hands out read-only views of JAX buffers, and SB3 passes
        # observations to torch.as_tensor, which warns on (and cannot protect) read-only memory.
        return np.array(obs)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> VecEnvStepReturn:
        if self._actions is None:
            raise RuntimeError("step_wait() needs a step_async(actions) first")
        actions, self._actions = self._actions, None
        obs, reward, terminated, truncated, info = self.vector_env.step(actions)
        dones = terminated | truncated
        infos = _split_info(info, self.num_envs)
        ended = np.flatnonzero(dones)
        if ended.size:
            final_infos = _split_info(info["final_info"], self.num_envs)
            for i in ended:
                self.reset_infos[i] = infos[i]
                infos[i] = final_infos[i]
                infos[i]["terminal_observation"] = np.array(info["final_obs"][i])
        time_limit = (truncated & ~terminated).tolist()
        for i, item in enumerate(infos):
            item["TimeLimit.truncated"] = time_limit[i]
        # Copies: SB3's on-policy loop adds the bootstrapped value of truncated episodes into
        # `rewards` in place, and the JAX-backed views are read-only.
        return np.array(obs), np.array(reward), dones, infos

    def close(self) -> None:
        self.vector_env.close()

    def get_images(self) -> list[np.ndarray | None]:
        """One RGB frame per env (`render_mode="rgb_array"`), for `render()` and `VecVideoRecorder`."""
        if self.render_mode != "rgb_array":
            warnings.warn(f"get_images() needs render_mode='rgb_array', got {self.render_mode!r}; returning None")
            return [None] * self.num_envs
        return list(self.vector_env.render())

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        value = getattr(self.vector_env, attr_name)  # AttributeError when missing, as SB3's has_attr expects
        return [value for _ in self._checked_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        if len(self._checked_indices(indices)) != self.num_envs:
            raise ValueError(f"set_attr({attr_name!r}) sets the attribute of the shared batched env: "
                             "pass indices=None (all envs), not a subset")
        setattr(self.vector_env, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices: VecEnvIndices = None, **method_kwargs) -> list[Any]:
        rows = self._checked_indices(indices)
        result = getattr(self.vector_env, method_name)(*method_args, **method_kwargs)
        return [result for _ in rows]

    def env_is_wrapped(self, wrapper_class: type[gymnasium.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        return [False for _ in self._checked_indices(indices)]  # no gymnasium.Wrapper around the batch

    # --- helpers ----------------------------------------------------------------------------

    def _seed_arg(self) -> list[int] | None:
        if all(seed is None for seed in self._seeds):
            return None
        if any(seed is None for seed in self._seeds):
            raise ValueError(f"seeds for the next reset must be given for every env or none, got {self._seeds}")
        # JAX PRNG seeds are uint32; VecEnv.seed(None) may draw up to 2**32 - 1 before adding i.
        return [int(seed) % MAX_SEED for seed in self._seeds]

    def _options_arg(self) -> dict | None:
        if all(not options for options in self._options):
            return None
        first = self._options[0]
        if any(set(options) != set(first) or any(not _same(options[k], first[k]) for k in first)
               for options in self._options[1:]):
            raise ValueError("the envs reset as one batch: set_options() must give every env the same options, "
                             "e.g. set_options({'reset_mask': mask})")
        return dict(first)

    def _checked_indices(self, indices: VecEnvIndices) -> list[int]:
        rows = list(self._get_indices(indices))
        bad = [i for i in rows if not 0 <= i < self.num_envs]
        if bad:
            raise IndexError(f"env indices must be in 0..{self.num_envs - 1}, got {bad}")
        return rows

    def __repr__(self) -> str:
        return f"OctaxSB3VecEnv({self.vector_env.game}, num_envs={self.num_envs})"


def _same(a, b) -> bool:
    return bool(np.array_equal(a, b)) if isinstance(a, np.ndarray) or isinstance(b, np.ndarray) else a == b


def _split_info(info: dict, num_envs: int) -> list[dict[str, Any]]:
    """A batched info dict (Gymnasium's, with `_` masks) -> one dict of Python scalars per env."""
    columns = {key: np.asarray(value).tolist() for key, value in info.items()
               if not key.startswith("_") and key not in ("final_obs", "final_info")}
    return [{key: column[i] for key, column in columns.items()} for i in range(num_envs)]


def make_sb3_vec_env(game: Any, num_envs: int, *, monitor: bool = True, **kwargs) -> VecEnv:
    """An `OctaxSB3VecEnv`, wrapped in SB3's `VecMonitor` unless `monitor=False`.

    `VecMonitor` adds `infos[i]["episode"] = {"r", "l", "t"}` when an episode ends, which PPO logs
    (rollout/ep_rew_mean) and `evaluate_policy` reads, as `make_vec_env`'s `Monitor` does.

    Args:
        game: a registered game id ("Brix") or a `GameSpec`.
        num_envs: number of envs.
        monitor: wrap in `VecMonitor`.
        **kwargs: `OctaxSB3VecEnv` keywords (render_mode, max_episode_steps, ...).

    >>> venv = make_sb3_vec_env("Pong", 8)
    >>> venv.reset().shape, venv.observation_space.dtype
    ((8, 4, 32, 64), dtype('uint8'))
    """
    venv = OctaxSB3VecEnv(game, num_envs, **kwargs)
    return VecMonitor(venv) if monitor else venv


# --- the paper's network and PPO settings --------------------------------------------------------

class OctaxCNNExtractor(BaseFeaturesExtractor):
    """The paper's CNN (`octax_gym.networks.OctaxCNN`) as an SB3 features extractor.

    The torso takes (frames, 32, 64) frames, swaps them to octax's width-first (frames, 64, 32)
    and applies the paper's convolutions: 15 x 15 x 32 -> 6 x 6 x 64 -> 4 x 4 x 64, flattened to
    1024; then Linear(1024, head_dim) + ReLU. SB3 has already divided the uint8 frames by 255.

    Args:
        observation_space: a Box of shape (frames, 32, 64).
        head_dim: units of the linear head; None for the 1024 conv features alone (what
            `ppo_kwargs` uses, with the 256-unit actor and critic layers in `net_arch`).
    """

    def __init__(self, observation_space: gymnasium.spaces.Box, head_dim: int | None = 256):
        shape = tuple(observation_space.shape)
        if len(shape) != 3 or shape[1:] != (32, 64):
            raise ValueError(f"OctaxCNNExtractor takes observations of shape (frames, 32, 64), got {shape}")
        super().__init__(observation_space, head_dim or FEATURES)
        self.torso = OctaxCNN(frames=shape[0], obs_scale=1)
        self.head = (torch.nn.Sequential(torch.nn.Linear(FEATURES, head_dim), torch.nn.ReLU()) if head_dim
                     else torch.nn.Identity())

    def forward(self, observations: torch.Tensor) -> torch.Tensor:
        return self.head(self.torso(observations))


# The paper's PPO (512 envs, 32-step rollouts, 4 epochs, 32 minibatches); `ppo_kwargs` maps it to SB3.
PAPER_PPO = {"num_envs": 512, "n_steps": 32, "n_epochs": 4, "num_minibatches": 32, "learning_rate": 5e-4,
             "gamma": 0.99, "gae_lambda": 0.95, "clip_range": 0.2, "vf_coef": 0.5, "ent_coef": 0.01,
             "max_grad_norm": 0.5}


def ppo_kwargs(num_envs: int = PAPER_PPO["num_envs"], num_minibatches: int = PAPER_PPO["num_minibatches"]) -> dict:
    """Keyword arguments for `PPO("CnnPolicy", venv, **ppo_kwargs(venv.num_envs))`, the paper's setup.

    batch_size = num_envs * n_steps / num_minibatches (at least 2, SB3's minimum), so every
    rollout is split into `num_minibatches` minibatches whatever the number of envs. Each call
    returns fresh dicts. The mapping and its approximations are in docs/sb3.md.
    """
    p = PAPER_PPO
    return {
        "n_steps": p["n_steps"], "batch_size": max(2, num_envs * p["n_steps"] // num_minibatches),
        "n_epochs": p["n_epochs"], "learning_rate": p["learning_rate"], "gamma": p["gamma"],
        "gae_lambda": p["gae_lambda"], "clip_range": p["clip_range"], "ent_coef": p["ent_coef"],
        # The paper's value loss is vf_coef * 0.5 * MSE; SB3's is vf_coef * MSE.
        "vf_coef": p["vf_coef"] * 0.5, "max_grad_norm": p["max_grad_norm"],
        "policy_kwargs": {
            # Shared conv torso (1024 features), then separate 256-unit ReLU layers for actor and critic.
            "features_extractor_class": OctaxCNNExtractor, "features_extractor_kwargs": {"head_dim": None},
            "share_features_extractor": True, "net_arch": {"pi": [256], "vf": [256]},
            "activation_fn": torch.nn.ReLU,
            "optimizer_kwargs": {"eps": 1e-8},  # optax.adam's default; SB3's own default is 1e-5
        },
    }


# For the paper's 512 envs (batch_size 512). With N envs, a multiple of 16, it still runs, in N / 16
# minibatches a rollout instead of 32; ppo_kwargs(N) keeps the 32.
PPO_KWARGS = ppo_kwargs()
