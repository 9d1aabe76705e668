"""backend="numpy" | "jax" | "torch": outputs handed over without copies, dtypes kept."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from counter_game import COUNTER
from octax_gym import OctaxEnv, OctaxVectorEnv

torch = pytest.importorskip("torch", reason="the torch extra is installed by `make test`")


def test_torch_tensors_share_memory_with_the_jax_buffers(counter_rom):
    envs = OctaxVectorEnv(COUNTER, 3, rom=counter_rom, backend="torch")
    obs, info = envs.reset(seed=0)
    assert isinstance(obs, torch.Tensor) and obs.data_ptr() == envs._obs.unsafe_buffer_pointer()
    obs, reward, terminated, truncated, info = envs.step(torch.tensor([0, 1, 2]))
    # The step's JAX outputs are the tensors' memory: no copy was made on the way.
    assert obs.data_ptr() == envs._obs.unsafe_buffer_pointer()
    assert (obs.dtype, reward.dtype, terminated.dtype, truncated.dtype) == (
        torch.uint8, torch.float32, torch.bool, torch.bool)
    assert (info["score"].dtype, info["lives"].dtype) == (torch.float32, torch.int32)
    assert obs.shape == (3, 4, 32, 64) and obs.device.type == "cpu"
    assert reward.tolist() == [0.0, 4.0, 8.0]


def test_torch_tensor_is_a_view_not_a_copy(counter_rom):
    """Writing through the tensor shows in the JAX array: the same bytes."""
    envs = OctaxVectorEnv(COUNTER, 2, rom=counter_rom, backend="torch")
    obs, _ = envs.reset(seed=0)
    jax_obs = envs._obs
    before = int(np.asarray(jax_obs)[1, 0, 0, 0])
    obs[1, 0, 0, 0] = 7
    assert before != 7 and int(np.asarray(jax_obs)[1, 0, 0, 0]) == 7


def test_numpy_backend_views_the_buffer(counter_rom):
    envs = OctaxVectorEnv(COUNTER, 2, rom=counter_rom)
    obs, _ = envs.reset(seed=0)
    assert isinstance(obs, np.ndarray)
    assert obs.__array_interface__["data"][0] == envs._obs.unsafe_buffer_pointer()


def test_jax_backend_returns_jax_arrays_and_takes_jax_actions(counter_rom):
    envs = OctaxVectorEnv(COUNTER, 2, rom=counter_rom, backend="jax")
    obs, info = envs.reset(seed=0)
    assert isinstance(obs, jax.Array) and isinstance(info["score"], jax.Array)
    obs, reward, *_ = envs.step(jax.numpy.array([2, 1]))
    assert isinstance(reward, jax.Array) and reward.tolist() == [8.0, 4.0]


def test_device_argument(counter_rom):
    envs = OctaxVectorEnv(COUNTER, 2, rom=counter_rom, backend="torch", device="cpu")
    obs, _ = envs.reset(seed=0)
    assert envs.device == jax.devices("cpu")[0] and obs.device.type == "cpu"
    envs = OctaxVectorEnv(COUNTER, 2, rom=counter_rom, device=torch.device("cpu"))
    assert envs.device.platform == "cpu"
    if not any(d.platform == "gpu" for d in jax.devices()):
        with pytest.raises(ValueError, match="unavailable device 'cuda'.*valid: 'cpu:0'"):
            OctaxVectorEnv(COUNTER, 2, rom=counter_rom, device="cuda")
    with pytest.raises(ValueError, match="unknown or unavailable device 'cpu:7'"):
        OctaxVectorEnv(COUNTER, 2, rom=counter_rom, device="cpu:7")


def test_single_env_backends(counter_rom):
    env = OctaxEnv(COUNTER, rom=counter_rom, backend="torch")
    obs, info = env.reset(seed=0)
    assert isinstance(obs, torch.Tensor) and obs.shape == (4, 32, 64) and info["score"] == 0
    obs, reward, terminated, truncated, info = env.step(torch.tensor(2))
    assert (reward, terminated, truncated, info["score"]) == (8.0, False, False, 8.0)
    assert type(reward) is float and type(terminated) is bool
