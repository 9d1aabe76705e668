"""Where arrays live and what type users get: `backend` ("numpy", "jax", "torch") and `device`.

The env computes with JAX on one device. Its outputs are handed over without copies: numpy gets
`np.asarray` of the CPU buffer (a read-only view), torch gets `torch.from_dlpack` (the tensor
shares the JAX buffer, on the GPU too), jax gets the arrays themselves. torch is imported only
when the torch backend, or a torch action, is used.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

BACKENDS = ("numpy", "jax", "torch")


def check_backend(backend: str) -> str:
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}; valid: {', '.join(BACKENDS)}")
    if backend == "torch":
        try:
            import torch  # noqa: F401
        except ImportError as exc:
            raise ImportError("backend='torch' needs torch: pip install 'octax-gym[torch]' "
                              "(which pins the CPU build torch==2.13.0)") from exc
    return backend


def resolve_device(device: Any) -> jax.Device:
    """None (JAX's default), a jax.Device, a torch.device, or "cpu", "gpu", "cuda", "cuda:1", "tpu"."""
    if device is None:
        return jax.devices()[0]
    if isinstance(device, jax.Device):
        return device
    text = str(device)  # torch.device("cuda:0") prints as "cuda:0"
    platform, _, index = text.partition(":")
    platform = {"cuda": "gpu", "rocm": "gpu"}.get(platform.lower(), platform.lower())
    available = [f"{d.platform}:{d.id}" for d in jax.devices()] + [f"cpu:{d.id}" for d in _cpu_devices()]
    try:
        devices = jax.devices(platform)
    except RuntimeError:
        devices = []
    if not index.isdigit() and index:
        devices = []
    position = int(index) if index else 0
    if position >= len(devices):
        raise ValueError(f"unknown or unavailable device {device!r}; available: {', '.join(dict.fromkeys(available))}")
    return devices[position]


def _cpu_devices():
    try:
        return jax.devices("cpu")
    except RuntimeError:
        return []


def to_backend(tree, backend: str):
    """Converts every array in a pytree (dicts of arrays) to the backend's type, without copies."""
    if backend == "jax":
        return tree
    if backend == "numpy":
        return jax.tree.map(np.asarray, tree)
    import torch

    return jax.tree.map(torch.from_dlpack, tree)


def actions_to_device(actions, num_envs: int, num_actions: int, device: jax.Device,
                      game: str) -> tuple[jax.Array, bool]:
    """A batch of actions (numpy, list, jax or torch) as an int32 JAX array on the env's device.

    Everything is checked that can be without waiting for a device: the type, the integer
    dtype and the shape (num_envs,) always, from metadata; the values too when they are on the
    host (numpy, lists). JAX arrays and torch tensors are never read here: their range is checked
    inside the jitted step (`octax_gym.action_check`).

    Returns:
        The actions, and whether their values are still unchecked (device inputs).

    Raises:
        TypeError: wrong type or dtype. ValueError: wrong shape or a host value out of range.
    """
    torch = _torch_if_tensor(actions)
    if torch is not None:
        if actions.dtype.is_floating_point or actions.dtype.is_complex or actions.dtype == torch.bool:
            raise TypeError(f"{game}: actions must be integers, got a torch tensor of {actions.dtype}")
        _check_shape(tuple(actions.shape), num_envs, game)
        # A private int32 copy (an async op on the tensor's stream), handed over by DLPack: the
        # caller may overwrite its tensor while the step still runs, and no value is read here.
        copy = actions.detach().to(dtype=torch.int32, copy=True).contiguous()
        return jax.device_put(jax.dlpack.from_dlpack(copy), device), True
    if isinstance(actions, jax.Array):
        _check_integer_dtype(actions.dtype, num_envs, num_actions, game)
        _check_shape(actions.shape, num_envs, game)
        return jax.device_put(actions.astype(jnp.int32), device), True
    array = np.asarray(actions)
    _check_integer_dtype(array.dtype, num_envs, num_actions, game)
    _check_shape(array.shape, num_envs, game)
    if array.size and (array.min() < 0 or array.max() >= num_actions):
        bad = array.min() if array.min() < 0 else array.max()
        raise ValueError(f"{game}: action {bad} is out of range; valid actions are 0..{num_actions - 1}")
    return jax.device_put(array.astype(np.int32), device), False


def _check_integer_dtype(dtype, num_envs: int, num_actions: int, game: str) -> None:
    if not np.issubdtype(dtype, np.integer) or dtype == np.bool_:
        raise TypeError(f"{game}: actions must be integers, got {dtype} "
                        f"(expected shape ({num_envs},), values 0..{num_actions - 1})")


def _check_shape(shape: tuple, num_envs: int, game: str) -> None:
    if tuple(shape) != (num_envs,):
        raise ValueError(f"{game}: actions must have shape ({num_envs},), one per env, got {tuple(shape)}")


def action_to_int(action, num_actions: int, game: str) -> int:
    """One action (python int, numpy integer, 0-d array or tensor) -> int, checked."""
    torch = _torch_if_tensor(action)
    value = action.detach().cpu().numpy() if torch is not None else np.asarray(action)
    if value.shape != () or not np.issubdtype(value.dtype, np.integer) or value.dtype == np.bool_:
        raise TypeError(f"{game}: an action is one integer in 0..{num_actions - 1}, "
                        f"got {value.dtype} of shape {value.shape}")
    if not 0 <= int(value) < num_actions:
        raise ValueError(f"{game}: action {int(value)} is out of range; valid actions are 0..{num_actions - 1}")
    return int(value)


def _torch_if_tensor(value):
    """The torch module when `value` is a torch tensor (without importing torch otherwise)."""
    module = type(value).__module__
    if module.startswith("torch"):
        import torch

        if isinstance(value, torch.Tensor):
            return torch
    return None
