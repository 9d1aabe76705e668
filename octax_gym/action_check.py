"""Every check of an action, in one place: host actions at once, device ones without a wait.

Every way an action reaches a game goes through here: `OctaxVectorEnv.step` (and the SB3 and
TorchRL adapters above it) by `to_device`, `OctaxEnv.step` by `to_int`, the dataset collector's
policy outputs by `check_batch`, so a bad action gets the same error, with the same words,
whatever brought it: TypeError for a wrong type or dtype, ValueError for a wrong shape, and
`InvalidActionError` (a ValueError) for a value outside 0..num_actions-1.

Actions that arrive on the host (numpy arrays, lists, ints) are checked before the step, on the
host: an out-of-range one raises at once and nothing runs. Actions that arrive as JAX arrays or
torch tensors may still be being computed (JAX and CUDA run asynchronously), and reading them
would make every step wait for the device: a sync per step, the cost a GPU pipeline exists to
avoid. So their shape and dtype are checked from metadata, and their range inside the jitted step,
which keeps a report on the device: how many out-of-range actions arrived since the last check,
and the first one (env, value). Those envs hold no key for that step.

The host reads a report only once the device has finished computing it (`jax.Array.is_ready`),
so reading never waits; `InvalidActionError` is raised at the first `step()` or `reset()` call
after that, and by `close()` at the latest. With the numpy backend every step's outputs are
read back anyway, so the report is read with them and the error comes from the very step that
received the action. If the host runs more than `MAX_PENDING` steps ahead of the device, the
oldest report is waited for: the device is that far behind, so the wait costs nothing.
"""

from __future__ import annotations

import collections
from typing import Any, Optional

import jax
import jax.numpy as jnp
import numpy as np

MAX_PENDING = 64
NO_REPORT = (0, -1, 0)  # (out-of-range actions, first env, its action)


class InvalidActionError(ValueError):
    """An action outside 0..num_actions-1; the message names it, its env and the valid range."""


# --- on the host, before the step ---------------------------------------------------------------


def to_device(actions, num_envs: int, num_actions: int, device: jax.Device,
              game: str) -> tuple[jax.Array, bool]:
    """A batch of actions (numpy, list, jax or torch) as an int32 JAX array on the env's device.

    Everything is checked that can be without waiting for a device: the type, the integer
    dtype and the shape (num_envs,) always, from metadata; the values too when they are on the
    host (numpy, lists). JAX arrays and torch tensors are never read here: their range is checked
    inside the jitted step (`accumulate`, `DeferredCheck`).

    Returns:
        The actions, and whether their values are still unchecked (device inputs).

    Raises:
        TypeError: wrong type or dtype. ValueError: wrong shape. InvalidActionError: a host
        value out of range.
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
    array = check_batch(actions, num_envs, num_actions, game)
    return jax.device_put(array.astype(np.int32), device), False


def check_batch(actions: Any, num_envs: int, num_actions: int, game: str, source: str = "") -> np.ndarray:
    """A batch of actions read on the host (`np.asarray`), checked: integers, shape (num_envs,),
    values in 0..num_actions-1. `source` says where they came from ("from the policy").

    Raises:
        TypeError: not integers. ValueError: wrong shape. InvalidActionError: a value out of range.
    """
    who = f"{game}, {source}" if source else game
    array = np.asarray(actions)
    _check_integer_dtype(array.dtype, num_envs, num_actions, who)
    _check_shape(array.shape, num_envs, who)
    if array.size and (array.min() < 0 or array.max() >= num_actions):
        raise _out_of_range(array.min() if array.min() < 0 else array.max(), num_actions, who)
    return array


def to_int(action: Any, num_actions: int, game: str) -> int:
    """One action (python int, numpy integer, 0-d array or tensor) -> int, checked.

    Raises:
        TypeError: not one integer. InvalidActionError: out of range.
    """
    torch = _torch_if_tensor(action)
    value = action.detach().cpu().numpy() if torch is not None else np.asarray(action)
    if value.shape != () or not np.issubdtype(value.dtype, np.integer) or value.dtype == np.bool_:
        raise TypeError(f"{game}: an action is one integer in 0..{num_actions - 1}, "
                        f"got {value.dtype} of shape {value.shape}")
    if not 0 <= int(value) < num_actions:
        raise _out_of_range(int(value), num_actions, game)
    return int(value)


def _check_integer_dtype(dtype, num_envs: int, num_actions: int, who: str) -> None:
    if not np.issubdtype(dtype, np.integer) or dtype == np.bool_:
        raise TypeError(f"{who}: actions must be integers, got {dtype} "
                        f"(expected shape ({num_envs},), values 0..{num_actions - 1})")


def _check_shape(shape: tuple, num_envs: int, who: str) -> None:
    if tuple(shape) != (num_envs,):
        raise ValueError(f"{who}: actions must have shape ({num_envs},), one per env, got {tuple(shape)}")


def _out_of_range(value: int, num_actions: int, who: str, detail: str = "") -> InvalidActionError:
    """The one wording of an out-of-range action, host or device."""
    return InvalidActionError(f"{who}: action {value} is out of range; valid actions are 0..{num_actions - 1}{detail}")


def _torch_if_tensor(value):
    """The torch module when `value` is a torch tensor (without importing torch otherwise)."""
    module = type(value).__module__
    if module.startswith("torch"):
        import torch

        if isinstance(value, torch.Tensor):
            return torch
    return None


# --- on the device, inside the step -------------------------------------------------------------


def accumulate(report: jax.Array, actions: jax.Array, num_actions: int) -> jax.Array:
    """The report after one more step's actions (traced in the jitted step).

    Args:
        report: int32 (3,): out-of-range actions so far, the first one's env and value.
        actions: int32 (num_envs,), the actions as given.
        num_actions: the valid range is 0..num_actions-1.
    """
    bad = (actions < 0) | (actions >= num_actions)
    first = jnp.argmax(bad)
    this_step = jnp.stack([bad.sum(dtype=jnp.int32), first.astype(jnp.int32), actions[first]])
    return jnp.where(report[0] > 0, report.at[0].add(this_step[0]), this_step)


class DeferredCheck:
    """The reports of one env's steps, read back when ready; see the module docstring."""

    def __init__(self, game: str, num_actions: int, device: jax.Device):
        self.game, self.num_actions = game, num_actions
        self._clean = jax.device_put(jnp.asarray(NO_REPORT, jnp.int32), device)
        self._pending: collections.deque[tuple[int, jax.Array]] = collections.deque()
        self._steps = 0

    @property
    def report(self) -> jax.Array:
        """The report the next step starts from: the last step's, until a check has read it."""
        return self._pending[-1][1] if self._pending else self._clean

    def record(self, report: jax.Array, values_unchecked: bool) -> None:
        """Keeps the report a step returned, if its actions still need checking."""
        self._steps += 1
        if values_unchecked:
            self._pending.append((self._steps, report))

    def poll(self, wait: bool = False) -> None:
        """Reads the newest finished report (every report with `wait`, and the oldest when more
        than MAX_PENDING are pending), then forgets the ones it covers.

        Raises:
            InvalidActionError: a report shows an out-of-range action.
        """
        if not self._pending:
            return
        ready: Optional[tuple[int, jax.Array]] = None
        while self._pending and (wait or len(self._pending) > MAX_PENDING or self._pending[0][1].is_ready()):
            ready = self._pending.popleft()  # each report covers every earlier one
        if ready is None:
            return
        count, env, value = (int(v) for v in jax.device_get(ready[1]))
        if count:
            self._pending.clear()  # the next step starts from a clean report
            raise _out_of_range(value, self.num_actions, self.game, (
                f" (env {env}, in a device array by step {ready[0]} of this env, whose "
                f"range is checked inside the jitted step (so that steps never wait for the device): "
                f"{count} out-of-range action(s) since the last check, each holding no key for its step)"))
