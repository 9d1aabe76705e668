"""Every check of an action, in one place: host actions at once, device ones without a wait.

Every way an action reaches a game goes through here: `OctaxVectorEnv.step` and
`MultiAgentVectorEnv.step` (and the SB3, TorchRL and PettingZoo adapters above them) by
`to_device`, `OctaxEnv.step` and each agent's action of a PettingZoo step by `to_int`, the
dataset collector's policy outputs and a function opponent's by `check_batch`, so a bad action
gets the same error, with the same words, whatever brought it: TypeError for a wrong type or
dtype, ValueError for a wrong shape, and `InvalidActionError` (a ValueError) for a value outside
0..num_actions-1. Every range check reads the value in the dtype it came in: a narrowing comes
after it, never before (the core's own check, `Env._check_action`, keeps the same rule).

Two-player games (`octax_gym.MultiAgentVectorEnv`, the PettingZoo envs, the single-agent view
against an opponent) take one action per env and seat, (num_envs, 2), checked the same way, the
messages naming the env and the seat (first_0, second_0); and an action that the game's legal
mask (`info["legal_action_mask"]`) closes, a move by the seat whose turn it is not, or one the
mover's `legal_fn` closes, raises `IllegalMoveError` (a ValueError): on the host before the step
for host actions, from the step's device report for device ones (where it is played as no-op).

Actions that arrive on the host (numpy arrays, lists, ints, torch tensors on the CPU, which torch
computes synchronously) are checked before the step, on the host: an out-of-range one raises at
once and nothing runs. Actions that arrive as JAX arrays or torch tensors on an accelerator may
still be being computed (JAX and CUDA run asynchronously), and reading them would make every step
wait for the device: a sync per step, the cost a GPU pipeline exists to avoid. So their shape and dtype are checked from metadata, and their range inside the jitted step,
which keeps a report on the device: how many out-of-range actions arrived since the last check,
and the first one (env, value). Those envs hold no key for that step.

Device actions reach the step as int32, narrowed on the device after their dtype is known and
before any value is: int8..int32 and uint8, uint16 exactly; a dtype wider than int32 (int64, which
torch policies give, uint32, uint64, JAX's int64 under `jax_enable_x64`) clamped to int32's range,
so that a value beyond it stays out of range (int64 2**32 + 1 -> 2**31 - 1, refused) instead of
wrapping onto a valid action (1). Their private copy as given is kept with the step's report and
read only when that report shows a bad action, so the error names the value given.

The host reads a report only once the device has finished computing it (`jax.Array.is_ready`),
so reading never waits; `InvalidActionError` is raised at the first `step()` or `reset()` call
after that, and by `close()` at the latest. With the numpy backend every step's outputs are
read back anyway, so the report is read with them and the error comes from the very step that
received the action. If the host runs more than `MAX_PENDING` steps ahead of the device, the
oldest report is waited for: the device is that far behind, so the wait costs nothing.
"""

from __future__ import annotations

import collections
from typing import Any, Callable, NamedTuple, Optional

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


class Turns(NamedTuple):
    """A turn-based game's state after the last step, read on the host to check host actions
    against it (`to_device(turns=...)`, `check_legal`)."""

    legal: np.ndarray  # bool (num_envs, seats, num_actions); (num_envs, num_actions): `seat`'s alone
    current_player: np.ndarray  # int (num_envs,): the seat to move
    done: np.ndarray  # bool (num_envs,): ended episodes, whose actions are ignored (not checked)
    agents: tuple[str, ...]  # the seats' names
    seat: Optional[int] = None  # the seat of a batch of one seat's actions (num_envs,) (a view)


class DeviceActions(NamedTuple):
    """A step's actions on the env's device (`to_device`)."""

    actions: jax.Array  # int32, (num_envs,) or (num_envs, seats)
    unchecked: bool  # their values are still unchecked (device inputs): the step's report checks them
    given: Any = None  # a private copy of them as given, where their dtype is wider than int32 (see above)


def to_device(actions, num_envs: int, num_actions: int, device: jax.Device, game: str,
              agents: Optional[tuple[str, ...]] = None,
              turns: Optional[Callable[[], Turns]] = None) -> DeviceActions:
    """A batch of actions (numpy, list, jax or torch) as an int32 JAX array on the env's device:
    the one way the vector, multi-agent and PettingZoo envs bring actions to their step.

    `agents`, the seats' names, for a two-player batch of shape (num_envs, len(agents)).
    `turns`, for a turn-based game: the last step's `Turns`, asked for (and so read from the
    device) only when the actions are on the host.

    Everything is checked that can be without waiting for a device: the type, the integer
    dtype and the shape (num_envs,) always, from metadata; the values too when they are on the
    host (numpy, lists, CPU tensors), against `turns` as well. JAX arrays and accelerator tensors
    are never read here: their range is checked inside the jitted step (`accumulate`, `DeferredCheck`), after a
    narrowing that keeps an out-of-range value out of range (see the module docstring).

    Raises:
        TypeError: wrong type or dtype. ValueError: wrong shape. InvalidActionError: a host
        value out of range. IllegalMoveError: a host action `turns` closes.
    """
    torch = _torch_if_tensor(actions)
    if torch is not None:
        if actions.dtype.is_floating_point or actions.dtype.is_complex or actions.dtype == torch.bool:
            raise TypeError(f"{game}: actions must be integers, got a torch tensor of {actions.dtype}")
        _check_shape(tuple(actions.shape), num_envs, game, agents)
        if _in_host_memory(actions):  # torch computes CPU tensors synchronously: reading one never waits
            actions = actions.detach().numpy()  # checked below as numpy is, at once; copied by astype
        else:
            narrowed, given = _torch_int32(actions.detach(), torch)
            return DeviceActions(jax.device_put(jax.dlpack.from_dlpack(narrowed), device), True, given)
    if isinstance(actions, jax.Array):
        _check_integer_dtype(actions.dtype, num_envs, num_actions, game, agents)
        _check_shape(actions.shape, num_envs, game, agents)
        if _fits_int32(np.iinfo(actions.dtype)):
            return DeviceActions(jax.device_put(actions.astype(jnp.int32), device), True)
        with _enable_x64(True):  # else JAX would first make an int64 array int32, by wrapping
            narrowed = _clamp_to_int32(actions)
        return DeviceActions(jax.device_put(narrowed, device), True, actions)  # immutable: no copy needed
    array = check_batch(actions, num_envs, num_actions, game, agents=agents)
    if turns is not None:
        check_legal(array, turns(), game)
    return DeviceActions(jax.device_put(array.astype(np.int32), device), False)


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
    function opponent returns (`octax_gym.step.opponent`), checked afterwards by `check_batch`."""
    if _torch_if_tensor(actions) is not None:
        return actions.detach().cpu().numpy()
    if isinstance(actions, jax.Array):
        return np.asarray(actions)
    if isinstance(actions, (list, tuple)):
        return np.array([to_host(value) for value in actions])
    return actions


def check_legal(actions: np.ndarray, turns: Turns, game: str) -> None:
    """Checks host actions, already in range, against the legal mask the last step gave
    (`info["legal_action_mask"]`): (num_envs, seats) actions, or (num_envs,) of `turns.seat`
    alone. Rows whose episode has ended (`turns.done`: their actions are ignored) are not checked.

    Raises:
        IllegalMoveError: a closed action; the message names the env, the seat, whose turn it is
            and the open actions.
    """
    legal, agents = np.asarray(turns.legal, np.bool_), turns.agents  # an info's action_mask is int8
    if turns.seat is not None:  # one seat's actions, the others' left open (an opponent's are its own)
        seats = np.zeros((len(actions), len(agents)), actions.dtype)
        seats[:, turns.seat] = actions
        open_actions = np.ones((*seats.shape, legal.shape[-1]), np.bool_)
        open_actions[:, turns.seat] = legal
        actions, legal = seats, open_actions
    closed = ~np.take_along_axis(legal, actions[..., None].astype(np.intp), axis=-1)[..., 0]
    closed &= ~turns.done[:, None]
    if closed.any():
        env, seat = np.argwhere(closed)[0]
        raise _illegal(game, agents, int(env), int(seat), int(actions[env, seat]), int(turns.current_player[env]),
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


def to_int(action: Any, num_actions: int, game: str, agent: Optional[str] = None) -> int:
    """One action (python int, numpy integer, 0-d array or tensor) -> int, checked: the single
    env's action, or `agent`'s in a PettingZoo step (the message then names the agent).

    Raises:
        TypeError: not one integer. InvalidActionError: out of range.
    """
    value = np.asarray(to_host(action))
    if value.shape != () or not np.issubdtype(value.dtype, np.integer):
        whose = "an action" if agent is None else f"{agent}'s action"
        raise TypeError(f"{game}: {whose} is one integer in 0..{num_actions - 1}, "
                        f"got {value.dtype} of shape {value.shape}")
    if not 0 <= int(value) < num_actions:
        raise _out_of_range(int(value), num_actions, game, "" if agent is None else f" (seat {agent})")
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


def _in_host_memory(tensor) -> bool:
    """A torch tensor in the host's memory (on the CPU), whose values exist by the time torch
    returns it; a CUDA tensor may still be being computed, and reading it would wait for the GPU."""
    return tensor.device.type == "cpu"


def _torch_if_tensor(value):
    """The torch module when `value` is a torch tensor (without importing torch otherwise)."""
    module = type(value).__module__
    if module.startswith("torch"):
        import torch

        if isinstance(value, torch.Tensor):
            return torch
    return None


INT32 = np.iinfo(np.int32)
# JAX's 64-bit mode for one block: `jax.enable_x64` from JAX 0.8, `jax.experimental.enable_x64` before.
if hasattr(jax, "enable_x64"):
    _enable_x64 = jax.enable_x64
else:  # JAX before 0.8
    from jax.experimental import enable_x64 as _enable_x64


def _fits_int32(limits) -> bool:
    """Whether every value of an integer dtype (its `iinfo`) is an int32: narrowing it is exact."""
    return INT32.min <= limits.min and limits.max <= INT32.max


def _torch_int32(actions, torch):
    """A tensor of actions as a private int32 copy, made by async ops on its stream (nothing read:
    the caller may overwrite its tensor while the step still runs), and a private copy as given
    where the dtype is wider than int32 (else None); see the module docstring."""
    if _fits_int32(torch.iinfo(actions.dtype)):
        return actions.to(dtype=torch.int32, copy=True).contiguous(), None
    given = actions.clone()
    signed = given if given.dtype == torch.int64 else given.to(torch.int64)  # torch clamps no uint32/64
    return signed.clamp(int(INT32.min), int(INT32.max)).to(torch.int32).contiguous(), given


@jax.jit
def _clamp_to_int32(actions: jax.Array) -> jax.Array:
    """A wide JAX array of actions (traced under `jax.enable_x64`) clamped to int32's range, then int32."""
    lowest = max(int(INT32.min), int(jnp.iinfo(actions.dtype).min))  # 0 for unsigned dtypes
    return jnp.clip(actions, lowest, int(INT32.max)).astype(jnp.int32)


def _given_value(given, env: int, seat: Optional[int]) -> Optional[int]:
    """The action as given at (env, seat) (`DeviceActions.given`, (num_envs,) or (num_envs, seats)):
    the exact value a report's clamped one stands for; None if the caller deleted its JAX array."""
    if isinstance(given, jax.Array):
        if given.is_deleted():
            return None
        values = np.asarray(jax.device_get(given))
    else:
        values = given.cpu().numpy()
    return int(values[env] if values.ndim == 1 else values[env, seat])


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
        self._pending: collections.deque[tuple[int, jax.Array, Any]] = collections.deque()
        self._steps = 0

    @property
    def report(self) -> jax.Array:
        """The report the next step starts from: the last step's, until a check has read it."""
        return self._pending[-1][1] if self._pending else self._clean

    def record(self, report: jax.Array, values_unchecked: bool, given: Any = None) -> None:
        """Keeps the report a step returned, if its actions still need checking, with the private
        copy of the actions as given when they were wider than int32 (`DeviceActions.given`)."""
        self._steps += 1
        if values_unchecked:
            self._pending.append((self._steps, report, given))

    def poll(self, wait: bool = False) -> None:
        """Reads the newest finished report (every report with `wait`, and the oldest when more
        than MAX_PENDING are pending), then forgets the ones it covers.

        Raises:
            InvalidActionError: a report shows an out-of-range action.
            IllegalMoveError: a two-player report shows a closed one.
        """
        read: list[tuple[int, jax.Array, Any]] = []
        while self._pending and (wait or len(self._pending) > MAX_PENDING or self._pending[0][1].is_ready()):
            read.append(self._pending.popleft())  # each report covers every earlier one
        if not read:
            return
        count, env, value, *mover = (int(v) for v in jax.device_get(read[-1][1]))
        if not count:
            return
        self._pending.clear()  # the next step starts from a clean report
        seat = None
        if self.agents is not None:
            env, seat = divmod(env, len(self.agents))
        value = _first_given(read, env, seat, value)
        if self.agents is None:
            raise _out_of_range(value, self.num_actions, self.game, (
                f" (env {env}, in a device array by step {read[-1][0]} of this env, whose "
                f"range is checked inside the jitted step (so that steps never wait for the device): "
                f"{count} out-of-range action(s) since the last check, each holding no key for its step)"))
        detail = (f" (in a device array by step {read[-1][0]} of this env, checked inside the jitted step so that "
                  f"steps never wait for the device: {count} bad action(s) since the last check, each played "
                  f"as no-op)")
        if 0 <= value < self.num_actions:
            raise _illegal(self.game, self.agents, env, seat, value, mover[0], detail=detail)
        raise _out_of_range(value, self.num_actions, self.game, f" (env {env}, seat {self.agents[seat]}){detail}")


def _first_given(read: list[tuple[int, jax.Array, Any]], env: int, seat: Optional[int], value: int) -> int:
    """The first bad action's value as given: the report's `value` is its int32 narrowing, clamped
    where the actions were wider than int32, so those are read from the step that brought it (the
    first whose report counts one; an error path: the reads may wait)."""
    if all(given is None for _, _, given in read):
        return value
    for _, report, given in read:
        if int(jax.device_get(report)[0]):
            exact = None if given is None else _given_value(given, env, seat)
            return value if exact is None else exact
    return value
