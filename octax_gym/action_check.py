"""Range checks of actions that live on a device, raised without making the step wait for them.

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
from typing import Optional

import jax
import jax.numpy as jnp

MAX_PENDING = 64
NO_REPORT = (0, -1, 0)  # (out-of-range actions, first env, its action)


class InvalidActionError(ValueError):
    """An action outside 0..num_actions-1; the message names it, its env and the valid range."""


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
            raise InvalidActionError(
                f"{self.game}: action {value} is out of range; valid actions are 0..{self.num_actions - 1} "
                f"(env {env}, in a device array by step {ready[0]} of this env, whose "
                f"range is checked inside the jitted step (so that steps never wait for the device): "
                f"{count} out-of-range action(s) since the last check, each holding no key for its step)")
