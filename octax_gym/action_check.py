"""Every check of an action, in one place: host actions at once, device ones without a wait.

Every way an action reaches a game goes through here: `OctaxVectorEnv.step` (and the SB3 and
TorchRL adapters above it) by `to_device`, `OctaxEnv.step` by `to_int`, the dataset collector's
policy outputs by `check_batch`, so a bad action gets the same error, with the same words,
whatever brought it: TypeError for a wrong type or dtype, ValueError for a wrong shape, and
`InvalidActionError` (a ValueError) for a value outside 0..num_actions-1.

Two-player games (`octax_gym.MultiAgentVectorEnv`, the PettingZoo envs, the single-agent view
against an opponent) take one action per env and seat, (num_envs, 2), checked the same way, the
messages naming the env and the seat (first_0, second_0); and an action that the game's legal
mask (`info["legal_action_mask"]`) closes, a move by the seat whose turn it is not, or one the
mover's `legal_fn` closes, raises `IllegalMoveError` (a ValueError): on the host before the step
for host actions, from the step's device report for device ones (where it is played as no-op).

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
NO_SEATS_REPORT = (0, -1, 0, -1)  # two seats: (bad actions, first env * 2 + seat, its action, seat to move)


class InvalidActionError(ValueError):
    """An action outside 0..num_actions-1; the message names it, its env and the valid range."""


class IllegalMoveError(ValueError):
    """A two-player game's action that its legal mask closes now: a move by the seat whose turn it
    is not (that seat may only play 0, no-op), or one the mover's `Seats.legal_fn` closes; the
    message names the env, the seat, the action and the open ones."""


# --- on the host, before the step ---------------------------------------------------------------


def to_device(actions, num_envs: int, num_actions: int, device: jax.Device,
              game: str, agents: Optional[tuple[str, ...]] = None) -> tuple[jax.Array, bool]:
    """A batch of actions (numpy, list, jax or torch) as an int32 JAX array on the env's device.

    `agents`, the seats' names, for a two-player batch of shape (num_envs, len(agents)).

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
        _check_shape(tuple(actions.shape), num_envs, game, agents)
        # A private int32 copy (an async op on the tensor's stream), handed over by DLPack: the
        # caller may overwrite its tensor while the step still runs, and no value is read here.
        copy = actions.detach().to(dtype=torch.int32, copy=True).contiguous()
        return jax.device_put(jax.dlpack.from_dlpack(copy), device), True
    if isinstance(actions, jax.Array):
        _check_integer_dtype(actions.dtype, num_envs, num_actions, game, agents)
        _check_shape(actions.shape, num_envs, game, agents)
        return jax.device_put(actions.astype(jnp.int32), device), True
    array = check_batch(actions, num_envs, num_actions, game, agents=agents)
    return jax.device_put(array.astype(np.int32), device), False


def check_batch(actions: Any, num_envs: int, num_actions: int, game: str, source: str = "",
                agents: Optional[tuple[str, ...]] = None) -> np.ndarray:
    """A batch of actions read on the host (`np.asarray`), checked: integers, shape (num_envs,)
    (or (num_envs, len(agents)) for two seats named `agents`), values in 0..num_actions-1.
    `source` says where they came from ("from the policy").

    Raises:
        TypeError: not integers. ValueError: wrong shape. InvalidActionError: a value out of range
        (for two seats the message names the env and the seat).
    """
    who = f"{game}, {source}" if source else game
    array = np.asarray(actions)
    _check_integer_dtype(array.dtype, num_envs, num_actions, who, agents)
    _check_shape(array.shape, num_envs, who, agents)
    if array.size and (array.min() < 0 or array.max() >= num_actions):
        if agents is None:
            raise _out_of_range(array.min() if array.min() < 0 else array.max(), num_actions, who)
        env, seat = np.argwhere((array < 0) | (array >= num_actions))[0]
        raise _out_of_range(int(array[env, seat]), num_actions, who, f" (env {env}, seat {agents[seat]})")
    return array


def to_host(actions: Any) -> Any:
    """Actions of any kind (a torch tensor, a JAX array, a list of either) read to numpy; what a
    function opponent returns (`octax_gym.opponent`), checked afterwards by `check_batch`."""
    if _torch_if_tensor(actions) is not None:
        return actions.detach().cpu().numpy()
    if isinstance(actions, jax.Array):
        return np.asarray(actions)
    if isinstance(actions, (list, tuple)):
        return np.array([to_host(value) for value in actions])
    return actions


def check_legal(actions: np.ndarray, legal: np.ndarray, current_player: np.ndarray, game: str,
                agents: tuple[str, ...], skip: Optional[np.ndarray] = None) -> None:
    """Checks host actions (num_envs, seats), already in range, against the legal mask the last
    step gave (`info["legal_action_mask"]`, (num_envs, seats, num_actions)); rows in `skip` (ended
    episodes, whose actions are ignored) are not checked.

    Raises:
        IllegalMoveError: a closed action; the message names the env, the seat, whose turn it is
            and the open actions.
    """
    closed = ~np.take_along_axis(legal, actions[..., None].astype(np.intp), axis=-1)[..., 0]
    if skip is not None:
        closed &= ~skip[:, None]
    if closed.any():
        env, seat = np.argwhere(closed)[0]
        raise _illegal(game, agents, int(env), int(seat), int(actions[env, seat]), int(current_player[env]),
                       np.flatnonzero(legal[env, seat]).tolist())


def _illegal(game: str, agents: tuple[str, ...], env: int, seat: int, action: int, mover: int,
             open_actions: Optional[list[int]] = None, detail: str = "") -> IllegalMoveError:
    """The one wording of a closed action, host or device."""
    if 0 <= mover != seat:
        return IllegalMoveError(f"{game}: seat {agents[seat]} (env {env}) played action {action}, but it is "
                                f"{agents[mover]}'s turn: a seat whose turn it is not may only play 0 (no-op){detail}")
    listing = "" if open_actions is None else f"; open: {open_actions}"
    return IllegalMoveError(f"{game}: action {action} of seat {agents[seat]} (env {env}) is not legal now "
                            f"(info['legal_action_mask']){listing}{detail}")


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


def _check_integer_dtype(dtype, num_envs: int, num_actions: int, who: str,
                         agents: Optional[tuple[str, ...]] = None) -> None:
    if not np.issubdtype(dtype, np.integer) or dtype == np.bool_:
        shape = f"({num_envs},)" if agents is None else f"({num_envs}, {len(agents)})"
        raise TypeError(f"{who}: actions must be integers, got {dtype} "
                        f"(expected shape {shape}, values 0..{num_actions - 1})")


def _check_shape(shape: tuple, num_envs: int, who: str, agents: Optional[tuple[str, ...]] = None) -> None:
    if agents is None:
        if tuple(shape) != (num_envs,):
            raise ValueError(f"{who}: actions must have shape ({num_envs},), one per env, got {tuple(shape)}")
    elif tuple(shape) != (num_envs, len(agents)):
        raise ValueError(f"{who}: actions must have shape ({num_envs}, {len(agents)}), one per env and seat "
                         f"({', '.join(agents)}), got {tuple(shape)}")


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


def accumulate_seats(report: jax.Array, actions: jax.Array, open_actions: jax.Array, mover: jax.Array,
                     num_actions: int) -> jax.Array:
    """`accumulate` for two seats (traced in the jitted step): out-of-range and closed actions.

    Args:
        report: int32 (4,): bad actions so far, the first one's env * seats + seat, its value, and
            the seat to move in its env then (an in-range value is a closed one: IllegalMoveError).
        actions: int32 (num_envs, seats), the actions as given.
        open_actions: bool (num_envs, seats, num_actions), the actions each seat may play now
            (every one where an action is not checked: an ended episode's, an opponent's).
        mover: int32 (num_envs,), the seat to move (-1 in a simultaneous game).
    """
    in_range = (actions >= 0) & (actions < num_actions)
    is_open = jnp.take_along_axis(open_actions, jnp.where(in_range, actions, 0)[..., None], axis=-1)[..., 0]
    bad = (~in_range | ~is_open).reshape(-1)
    first = jnp.argmax(bad)
    this_step = jnp.stack([bad.sum(dtype=jnp.int32), first.astype(jnp.int32), actions.reshape(-1)[first],
                           mover[first // actions.shape[1]].astype(jnp.int32)])
    return jnp.where(report[0] > 0, report.at[0].add(this_step[0]), this_step)


class DeferredCheck:
    """The reports of one env's steps, read back when ready; see the module docstring.

    `agents`, the seats' names, for a two-player env's reports (`accumulate_seats`)."""

    def __init__(self, game: str, num_actions: int, device: jax.Device, agents: Optional[tuple[str, ...]] = None):
        self.game, self.num_actions, self.agents = game, num_actions, agents
        self._clean = jax.device_put(jnp.asarray(NO_REPORT if agents is None else NO_SEATS_REPORT, jnp.int32), device)
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
        count, env, value, *mover = (int(v) for v in jax.device_get(ready[1]))
        if not count:
            return
        self._pending.clear()  # the next step starts from a clean report
        if self.agents is None:
            raise _out_of_range(value, self.num_actions, self.game, (
                f" (env {env}, in a device array by step {ready[0]} of this env, whose "
                f"range is checked inside the jitted step (so that steps never wait for the device): "
                f"{count} out-of-range action(s) since the last check, each holding no key for its step)"))
        env, seat = divmod(env, len(self.agents))
        detail = (f" (in a device array by step {ready[0]} of this env, checked inside the jitted step so that "
                  f"steps never wait for the device: {count} bad action(s) since the last check, each played "
                  f"as no-op)")
        if 0 <= value < self.num_actions:
            raise _illegal(self.game, self.agents, env, seat, value, mover[0], detail=detail)
        raise _out_of_range(value, self.num_actions, self.game, f" (env {env}, seat {self.agents[seat]}){detail}")
