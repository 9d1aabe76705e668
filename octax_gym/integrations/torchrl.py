"""A native TorchRL environment over the batched JAX core: `make_torchrl_env`.

    from octax_gym.torchrl import make_torchrl_env
    env = make_torchrl_env("Brix", num_envs=64)             # an EnvBase with batch_size (64,)
    td = env.reset()                                          # td["observation"]: uint8 (64, 4, 32, 64)
    td = env.rand_step(td)                                    # td["next", "reward"]: float32 (64, 1)

TorchRL resets envs itself: `step_and_maybe_reset` (what its collectors and `rollout` call) sends
`reset()` a `"_reset"` mask of the rows that are done. Gymnasium's NEXT_STEP autoreset would
instead spend the next step on the reset, which TorchRL's `GymWrapper` refuses. So this env runs
the core without autoreset (`OctaxVectorEnv`'s DISABLED mode): a step is one jitted call, and a
reset with a mask is one jitted call that resets only the masked rows.

The tensors are the JAX buffers themselves, handed over by DLPack (no copy; on the GPU with
`device="cuda"`). This module is not imported by `import octax_gym`; importing it imports torch
and TorchRL. See docs/torchrl.md.
"""

from __future__ import annotations

from typing import Any, Optional

import jax
import jax.numpy as jnp
import numpy as np
import torch
from tensordict import TensorDict, TensorDictBase
from torchrl.data import Bounded, Categorical, Composite, Unbounded
from torchrl.envs import EnvBase

from octax_gym.envs.vector import OctaxVectorEnv
from octax_gym.step.compiled_step import seeds_for

# Keywords this adapter fixes itself: the core must not autoreset and must hand back torch tensors.
_FIXED = ("autoreset_mode", "backend")
INFO_KEYS = ("score", "lives", "episode_step")


class OctaxTorchRLEnv(EnvBase):
    """`num_envs` copies of one game (CHIP-8, SUPER-CHIP or XO-CHIP) as a batched TorchRL
    `EnvBase` (batch_size (num_envs,)).

    Specs (N = num_envs, F = frames_per_step; H, W = 32, 64 on CHIP-8, 64, 128 on SUPER-CHIP and
    XO-CHIP):
      observation: "observation" uint8 (N, F, H, W) in 0..the vector env's observation high
        (`Bounded`), the screen after each 60 Hz frame of the step; "score" float32 (N,), "lives" int32 (N,) (-1 where
        the game keeps none) and "episode_step" int32 (N,), the Gymnasium env's info.
      action: "action" int64 (N,) in 0..n-1 (`Categorical`); 0 holds no key, i the game's i-th key.
      reward: "reward" float32 (N, 1), the change of the game's score.
      done: "done", "terminated", "truncated" bool (N, 1).

    An env whose episode has ended stands still (same observation, reward 0, same flags) until
    `reset` resets it; TorchRL's collectors and `rollout` do so through the `"_reset"` mask.
    `set_seed(s)` makes the next reset seed env i with s + i (as `OctaxVectorEnv.reset(seed=s)`).

    Args:
        game: a registered game id ("Brix"; see `octax_core.list_games()`) or a `GameSpec`.
        num_envs: number of envs in the batch.
        device: where the env runs and its tensors live: None (JAX's default), "cpu", "cuda",
            "cuda:1", a torch.device or a jax.Device.
        **env_kwargs: the other `OctaxVectorEnv` keywords (frames_per_step, obs_scale,
            max_episode_steps, repeat_action_probability, noop_max, render_mode, rom, ...).

    Raises:
        TypeError: `autoreset_mode` or `backend` given (this adapter fixes both), or an
            unknown keyword.
    """

    def __init__(self, game: Any, num_envs: int = 1, *, device: Any = None, **env_kwargs):
        fixed = sorted(set(env_kwargs) & set(_FIXED))
        if fixed:
            raise TypeError(f"OctaxTorchRLEnv sets {fixed} itself (DISABLED autoreset, torch tensors); "
                            f"drop the keyword(s)")
        self.vector_env = OctaxVectorEnv(game, num_envs, autoreset_mode="disabled", backend="torch",
                                         device=device, **env_kwargs)
        super().__init__(device=_torch_device(self.vector_env.device), batch_size=(self.vector_env.num_envs,))
        self._make_specs()
        self._seed: Optional[int] = None
        self._obs = self._info = None
        self._flags = torch.zeros((2, self.vector_env.num_envs, 1), dtype=torch.bool, device=self.device)

    @property
    def num_envs(self) -> int:
        return self.vector_env.num_envs

    @property
    def game(self) -> str:
        return self.vector_env.game

    def _make_specs(self) -> None:
        n, shape = self.num_envs, self.vector_env.single_observation_space.shape
        high = int(self.vector_env.single_observation_space.high.max())
        scalar = {"shape": (n,), "device": self.device}
        self.observation_spec = Composite(
            observation=Bounded(0, high, shape=(n, *shape), dtype=torch.uint8, device=self.device),
            score=Unbounded(dtype=torch.float32, **scalar),
            lives=Unbounded(dtype=torch.int32, **scalar),
            episode_step=Unbounded(dtype=torch.int32, **scalar),
            shape=(n,), device=self.device)
        self.action_spec = Categorical(self.vector_env.single_action_space.n, shape=(n,), device=self.device)
        self.reward_spec = Unbounded(shape=(n, 1), dtype=torch.float32, device=self.device)
        flag = Categorical(2, shape=(n, 1), dtype=torch.bool, device=self.device)
        self.done_spec = Composite(done=flag, terminated=flag.clone(), truncated=flag.clone(),
                                   shape=(n,), device=self.device)

    # --- EnvBase hooks ---------------------------------------------------------------------

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        obs, reward, terminated, truncated, info = self.vector_env.step(tensordict.get("action"))
        self._obs, self._info = obs, info
        self._flags = torch.stack((terminated, truncated)).unsqueeze(-1)
        return self._output(reward=reward.unsqueeze(-1))

    def _reset(self, tensordict: Optional[TensorDictBase] = None, *, seed: Optional[int] = None,
               **unknown) -> TensorDictBase:
        """Resets every env, or only the rows where `tensordict["_reset"]` is True.

        `reset(seed=s)` seeds the envs it resets with s + i, as `set_seed(s)` followed by `reset()`.
        """
        if unknown:
            raise TypeError(f"OctaxTorchRLEnv.reset got unknown keyword(s) {sorted(unknown)}; valid: seed")
        if seed is not None:
            self._set_seed(seed)
        mask = None if tensordict is None else tensordict.get("_reset", None)
        if mask is not None:
            mask = mask.reshape(self.num_envs).cpu().numpy()  # the reset mask is read on the host
            if self._obs is None or mask.all():
                mask = None
            elif not mask.any():
                return self._output()  # nothing to reset: the current data, no device work
        seed, self._seed = self._seed, None
        options = None if mask is None else {"reset_mask": mask}
        self._obs, self._info = self.vector_env.reset(seed=seed, options=options)
        if mask is None:
            self._flags = torch.zeros_like(self._flags)
        else:
            self._flags = self._flags & ~torch.as_tensor(mask, device=self.device).reshape(1, -1, 1)
        return self._output()

    def _set_seed(self, seed: Optional[int]) -> None:
        """Env i draws from seed + i from the next reset on; None keeps each env's key chain."""
        if seed is not None:
            seeds_for(seed, self.num_envs)  # raises now on a bad seed, not at the next reset
        self._seed = seed

    def _output(self, **extra) -> TensorDictBase:
        terminated, truncated = self._flags
        source = {"observation": self._obs, **{k: self._info[k] for k in INFO_KEYS},
                  "terminated": terminated, "truncated": truncated, "done": terminated | truncated, **extra}
        return TensorDict(source, batch_size=self.batch_size, device=self.device)

    def __repr__(self) -> str:
        return f"OctaxTorchRLEnv({self.game}, num_envs={self.num_envs}, device={self.device})"


def make_torchrl_env(game: Any, num_envs: int = 1, *, device: Any = None, **env_kwargs) -> OctaxTorchRLEnv:
    """A batched TorchRL env for one game; see `OctaxTorchRLEnv` for the specs and keywords.

    >>> env = make_torchrl_env("Brix", num_envs=8)              # doctest: +SKIP
    >>> torchrl.envs.utils.check_env_specs(env)                 # doctest: +SKIP
    >>> rollout = env.rollout(100, break_when_any_done=False)   # doctest: +SKIP
    """
    return OctaxTorchRLEnv(game, num_envs, device=device, **env_kwargs)


def _torch_device(device: jax.Device) -> torch.device:
    """The torch device that DLPack puts this JAX device's arrays on."""
    return torch.from_dlpack(jax.device_put(jnp.zeros((), np.uint8), device)).device
