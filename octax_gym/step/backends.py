"""Where arrays live and what type users get: `backend` ("numpy", "jax", "torch") and `device`.

The env computes with JAX on one device. Its outputs are handed over without copies: numpy gets
`np.asarray` of the CPU buffer (a read-only view), torch gets `torch.from_dlpack` (the tensor
shares the JAX buffer, on the GPU too), jax gets the arrays themselves. torch is imported only
when the torch backend is used. Actions come the other way, checked: `octax_gym.step.action_check`.
"""

from __future__ import annotations

from typing import Any

import jax
import numpy as np

from octax_gym.envs.choices import UnknownOptionError, check_choice

BACKENDS = ("numpy", "jax", "torch")


def check_backend(backend: str) -> str:
    """`backend`, one of `BACKENDS` (torch installed for "torch").

    Raises:
        UnknownOptionError: another name. ImportError: "torch" without torch.
    """
    check_choice("backend", backend, BACKENDS)
    if backend == "torch":
        try:
            import torch  # noqa: F401
        except ImportError as exc:
            raise ImportError("backend='torch' needs torch: pip install 'octax-gym[torch]' "
                              "(which pins the CPU build torch==2.13.0)") from exc
    return backend


def resolve_device(device: Any) -> jax.Device:
    """None (JAX's default), a jax.Device, a torch.device, or "cpu", "gpu", "cuda", "cuda:1", "tpu".

    "cuda:1" is this process's second GPU, as in torch; in a multi-process run
    (`octax_gym.step.distributed`) a device's global name as JAX prints it ("cpu:2048") works too.

    Raises:
        UnknownOptionError: no such device in this process; the message lists the available ones.
    """
    if device is None:
        return jax.local_devices()[0]
    if isinstance(device, jax.Device):
        return device
    text = str(device)  # torch.device("cuda:0") prints as "cuda:0"
    platform, _, index = text.partition(":")
    platform = {"cuda": "gpu", "rocm": "gpu"}.get(platform.lower(), platform.lower())
    local = jax.local_devices()
    available = [f"{d.platform}:{d.id}" for d in local] + [f"cpu:{d.id}" for d in _cpu_devices() if d not in local]
    try:
        devices = jax.local_devices(backend=platform)
    except RuntimeError:
        devices = []
    if not index.isdigit() and index:
        devices = []
    position = int(index) if index else 0
    by_id = [d for d in devices if d.id == position]
    if by_id:
        return by_id[0]
    if position >= len(devices):
        raise UnknownOptionError("or unavailable device", device, dict.fromkeys(available),
                                 "or a jax.Device or torch.device")
    return devices[position]


def _cpu_devices():
    try:
        return jax.local_devices(backend="cpu")
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
