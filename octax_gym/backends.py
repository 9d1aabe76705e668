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


def actions_to_jax(actions, num_envs: int, num_actions: int, device: jax.Device, game: str) -> jax.Array:
    """Checks a batch of actions (numpy, list, jax or torch) and puts it on the env's device.

    The checks run on the host before the jitted step, which cannot raise: shape (num_envs,),
    an integer dtype, every value in 0..num_actions-1.

    Raises:
        TypeError: wrong type or dtype. ValueError: wrong shape or a value out of range.
    """
    torch = _torch_if_tensor(actions)
    if torch is not None:
        if actions.dtype.is_floating_point or actions.dtype.is_complex or actions.dtype == torch.bool:
            raise TypeError(f"{game}: actions must be integers, got a torch tensor of {actions.dtype}")
        shape, array = tuple(actions.shape), actions.detach()
        low, high = (int(array.min()), int(array.max())) if array.numel() else (0, 0)
        array = jax.dlpack.from_dlpack(array.contiguous()) if array.device.type != "cpu" else array.numpy()
    else:
        array = actions if isinstance(actions, (jax.Array, np.ndarray)) else np.asarray(actions)
        if not (np.issubdtype(array.dtype, np.integer)) or array.dtype == np.bool_:
            raise TypeError(f"{game}: actions must be integers, got {array.dtype} "
                            f"(expected shape ({num_envs},), values 0..{num_actions - 1})")
        shape = tuple(array.shape)
        host = np.asarray(array) if shape == (num_envs,) else None
        low, high = (int(host.min()), int(host.max())) if host is not None and host.size else (0, 0)
    if shape != (num_envs,):
        raise ValueError(f"{game}: actions must have shape ({num_envs},), one per env, got {shape}")
    if low < 0 or high >= num_actions:
        bad = low if low < 0 else high
        raise ValueError(f"{game}: action {bad} is out of range; valid actions are 0..{num_actions - 1}")
    return jax.device_put(jnp.asarray(array, jnp.int32) if isinstance(array, jax.Array)
                          else np.asarray(array, np.int32), device)


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
