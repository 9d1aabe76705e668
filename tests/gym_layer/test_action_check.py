"""Actions on a device are never read back on the step path, and a bad one still raises; the
host checks (last section) are the same module's, and every way an action comes in uses them.

On a CPU `jax.transfer_guard` sees no transfers (host and device memory are the same), so the
tests check what a read would cost instead: the actions come from a computation that is still
running when `step()` returns (reading them would have waited for it, and they would be ready),
the Python-level reads of an unfinished JAX array (`int()`, `.item()`, `.tolist()`, `bool()`,
`jax.device_get`: its `_value`) and every read of a torch tensor's values are made to fail. The
guard is set too, for a GPU.
"""

from __future__ import annotations

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax._src.array import ArrayImpl  # the one class behind jax.Array; its _value is every host read

import octax_gym
from counter_game import COUNTER
from octax_gym import OctaxVectorEnv
from octax_gym.step.action_check import (MAX_PENDING, DeferredCheck, InvalidActionError, accumulate, check_batch,
                                         to_device, to_int)


def _no_waiting_reads(monkeypatch):
    """From here on, a Python-level read of an unfinished JAX array's values raises: it would
    wait for the device. (The step path may read a finished action report, which waits for nothing.)"""
    value = ArrayImpl._value

    def read(self):
        if not self.is_ready():
            raise AssertionError("the step path read an unfinished device value back to the host")
        return value.fget(self)
    monkeypatch.setattr(ArrayImpl, "_value", property(read))


@jax.jit
def _slow_actions(actions):
    """`actions`, after a few seconds of matrix products that decide nothing."""
    m = jax.lax.fori_loop(0, 150, lambda i, m: jnp.tanh(m @ m / 1500.0), jnp.ones((1500, 1500), jnp.float32))
    return actions + (m[0, 0] > 2.0).astype(actions.dtype)  # tanh keeps it below 1: adds 0


@pytest.fixture
def make_envs(counter_rom):
    def build(backend, **kwargs):
        return OctaxVectorEnv(COUNTER, 3, rom=counter_rom, backend=backend, **kwargs)
    return build


@pytest.mark.slow  # 30 s of compiles; the host checks' tests above run in make test
def test_jax_actions_are_never_read_on_the_step_path(make_envs, monkeypatch):
    envs = make_envs("jax")
    envs.reset(seed=0)
    jax.block_until_ready(envs.step(jnp.array([0, 0, 0]))[0])  # compiled
    jax.block_until_ready(_slow_actions(jnp.zeros(3, jnp.int32)))  # compiled
    actions = _slow_actions(jnp.array([0, 1, 9]))  # 9 is out of range: found later, without reading it here
    with monkeypatch.context() as patch, jax.transfer_guard_device_to_host("disallow"):
        _no_waiting_reads(patch)
        for _ in range(3):
            obs, reward, terminated, truncated, info = envs.step(actions)
            assert isinstance(reward, jax.Array)
        envs.step(jnp.array([1, 1, 1]))
    assert not actions.is_ready(), "step() waited for the actions' computation"
    # The reports themselves, not the state: a report is read once it is ready, and on CI's CPU the
    # state came out ready while the first report did not yet (the error then came one call later).
    jax.block_until_ready([report for _, report, _ in envs._action_check._pending])
    with pytest.raises(InvalidActionError, match=r"action 9 is out of range; valid actions are 0\.\.2 \(env 2"):
        envs.step(jnp.array([0, 0, 0]))
    obs, reward, *_ = envs.step(jnp.array([2, 2, 2]))  # after the error, a clean report
    assert list(np.asarray(reward)) == [8.0, 8.0, 8.0]


def test_accelerator_torch_actions_are_never_read_on_the_step_path(make_envs, monkeypatch):
    """A tensor on an accelerator (a CUDA tensor, stood in for by one the check is told is not in
    host memory: no GPU here) may still be being computed: its range is checked on the device."""
    torch = pytest.importorskip("torch", reason="the torch extra is installed by `make test`")
    envs = make_envs("torch")
    envs.reset(seed=0)
    actions = torch.tensor([0, 5, 1])

    def read(*args, **kwargs):
        raise AssertionError("the step path read a torch action on the host")
    with monkeypatch.context() as patch, jax.transfer_guard_device_to_host("disallow"):
        patch.setattr("octax_gym.step.action_check._in_host_memory", lambda tensor: False)
        _no_waiting_reads(patch)
        for name in ("item", "tolist", "numpy", "__int__", "__index__", "__bool__", "__array__", "min", "max"):
            patch.setattr(torch.Tensor, name, read)
        obs, reward, *_ = envs.step(actions)
        actions[1] = 1  # the caller may reuse its tensor at once: the step took a private copy
        assert reward.dtype == torch.float32
    jax.block_until_ready(envs.state)
    with pytest.raises(InvalidActionError, match=r"action 5 is out of range; valid actions are 0\.\.2 \(env 1"):
        envs.reset(options={"reset_mask": np.ones(3, bool)})


@pytest.mark.parametrize("backend", ["torch", "jax"])
def test_a_cpu_torch_action_is_refused_by_the_step_that_gets_it(make_envs, backend):
    """A CPU tensor's values exist when torch returns it: checked at once on the host, as numpy is,
    so int64 2**32 + 1 (once wrapped to int32 and played as action 1) is refused before anything runs."""
    torch = pytest.importorskip("torch", reason="the torch extra is installed by `make test`")
    envs = make_envs(backend)
    envs.reset(seed=0)
    for value in (2**32 + 1, 5):
        with pytest.raises(InvalidActionError, match=rf"action {value} is out of range; valid actions are 0\.\.2"):
            envs.step(torch.tensor([0, value, 1], dtype=torch.int64))
    assert np.asarray(envs.step(torch.tensor([2, 1, 0]))[1]).tolist() == [8.0, 4.0, 0.0]


def test_numpy_backend_reports_a_bad_device_action_from_the_same_step(make_envs):
    envs = make_envs("numpy")
    envs.reset(seed=0)
    with pytest.raises(InvalidActionError, match="action -4 is out of range"):
        envs.step(jnp.array([0, -4, 1]))
    _, reward, *_ = envs.step(jnp.array([1, 1, 1]))
    assert list(reward) == [4.0, 4.0, 4.0]


def test_close_raises_what_no_step_read_yet(make_envs):
    envs = make_envs("jax")
    envs.reset(seed=0)
    envs.step(jnp.array([3, 0, 0]))
    with pytest.raises(InvalidActionError, match="action 3 is out of range"):
        envs.close()


def test_a_bad_action_holds_no_key_and_good_rows_play_on(make_envs):
    envs = make_envs("jax")
    envs.reset(seed=0)
    _, reward, *_ = envs.step(jnp.array([2, 7, 1]))
    assert list(np.asarray(reward)) == [8.0, 0.0, 4.0]
    with pytest.raises(InvalidActionError):
        envs.close()


def test_the_report_counts_and_keeps_the_first_bad_action():
    report = jnp.asarray((0, -1, 0), jnp.int32)
    report = accumulate(report, jnp.array([0, 1, 2]), 3)
    assert list(np.asarray(report)) == [0, 0, 0]
    report = accumulate(report, jnp.array([0, 4, -1]), 3)
    assert list(np.asarray(report)) == [2, 1, 4]
    report = accumulate(report, jnp.array([9, 0, 0]), 3)
    assert list(np.asarray(report)) == [3, 1, 4]  # the first one stays the one named


class _Unfinished(np.ndarray):
    """A report the device has not finished yet."""

    def is_ready(self):
        return False


def test_a_host_far_ahead_of_the_device_waits_for_the_oldest_report():
    check = DeferredCheck("Game", 3, jax.devices()[0])
    clean = np.array([0, -1, 0], np.int32)
    for _ in range(MAX_PENDING + 5):
        check.record(clean.view(_Unfinished), values_unchecked=True)
        check.poll()
    assert len(check._pending) == MAX_PENDING
    check.poll(wait=True)  # close(): everything is read
    assert not check._pending
    check.record(np.array([1, 2, 7], np.int32).view(_Unfinished), values_unchecked=True)
    with pytest.raises(InvalidActionError, match=r"action 7 is out of range; valid actions are 0\.\.2 \(env 2"):
        check.poll(wait=True)


# --- the host checks: every way in goes through this module ------------------------------------


@pytest.mark.parametrize("actions, error, message", [
    (np.array([0, 1, 3]), InvalidActionError,
     r"^Game, from the policy: action 3 is out of range; valid actions are 0\.\.2$"),
    (np.array([-1, 0, 0]), InvalidActionError, "action -1 is out of range"),
    (np.array([0.0, 1.0, 2.0]), TypeError, r"^Game, from the policy: actions must be integers, got float64"),
    (np.zeros((3, 1), np.int64), ValueError, r"actions must have shape \(3,\), one per env, got \(3, 1\)$"),
])
def test_a_host_batch_gets_the_env_s_errors(actions, error, message):
    with pytest.raises(error, match=message):
        check_batch(actions, 3, 3, "Game", "from the policy")
    assert check_batch([0, 2, 1], 3, 3, "Game").tolist() == [0, 2, 1]


def test_out_of_range_is_one_error_type_on_the_host_and_the_device():
    with pytest.raises(InvalidActionError, match=r"^Game: action 3 is out of range; valid actions are 0\.\.2$"):
        to_int(3, 3, "Game")
    with pytest.raises(InvalidActionError, match=r"^Game: action 5 is out of range; valid actions are 0\.\.2$"):
        to_device(np.array([0, 5]), 2, 3, jax.devices()[0], "Game")
    given = to_device(jnp.array([0, 5]), 2, 3, jax.devices()[0], "Game")
    assert given.unchecked and given.actions.dtype == jnp.int32  # its range: the step's report (above)


def test_the_envs_check_actions_only_through_this_module(counter_rom, monkeypatch):
    from octax_gym import OctaxEnv
    from octax_gym.step import action_check

    calls = []
    for name in ("to_device", "to_int"):
        checked = getattr(action_check, name)
        monkeypatch.setattr(action_check, name,
                            lambda *args, _checked=checked, _name=name: calls.append(_name) or _checked(*args))
    envs = OctaxVectorEnv(COUNTER, 3, rom=counter_rom)
    envs.reset(seed=0)
    envs.step(np.array([0, 1, 2]))
    env = OctaxEnv(COUNTER, rom=counter_rom)
    env.reset(seed=0)
    env.step(1)
    assert calls == ["to_device", "to_int", "to_device"]  # the single env's one action, then its batch of one


def test_no_other_module_of_the_user_layer_words_an_action_check():
    package = Path(octax_gym.__file__).parent
    wording = ("is out of range", "actions must", "an action is one integer")
    modules = sorted(path.relative_to(package).as_posix() for path in package.rglob("*.py")
                     if any(words in path.read_text() for words in wording))
    assert modules == ["step/action_check.py"]


# --- values beyond int32: the range is checked before any narrowing, in every backend and view ---

BACKENDS = ("numpy", "jax", "torch")
KINDS = ("numpy", "torch", "jax")  # how the actions come: host array, torch tensor, JAX array (int64)
# The two that wrapped onto 1 (narrowed first), and ordinary ones. make test tries one of each
# (2**32 + 1 and -1) on every (backend, kind, view); the other two, the same paths with the other
# sign, run in make test-slow.
BAD = (2**32 + 1, pytest.param(-2**32 + 1, marks=pytest.mark.slow), pytest.param(3, marks=pytest.mark.slow), -1)


def _int64(kind, values):
    """`values` as int64 actions of a kind; a JAX int64 array needs jax_enable_x64 to be made."""
    if kind == "numpy":
        return np.asarray(values, np.int64)
    if kind == "torch":
        torch = pytest.importorskip("torch", reason="the torch extra is installed by `make test`")
        return torch.tensor(values, dtype=torch.int64)
    with jax.enable_x64(True):
        return jnp.asarray(values, jnp.int64)


def _refused(envs, actions, message):
    """Steps `actions` and expects `message`: from this step (host actions, numpy backend) or, for
    device actions on the jax and torch backends, from `close()`; returns the step's rewards then."""
    rewards = None
    with pytest.raises(InvalidActionError, match=message):
        rewards = np.asarray(envs.step(actions)[1])
        envs.close()
    return rewards


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("value", BAD)
@pytest.mark.parametrize("view", ["vector", "mix"])
def test_a_vector_env_refuses_an_out_of_range_action_of_any_width(counter_rom, monkeypatch, backend, kind, value, view):
    if view == "mix":  # a one-game mix of Counter: its ROM from the store's search path
        monkeypatch.setenv("OCTAX_ROM_DIR", str(counter_rom.parent))
        envs = OctaxVectorEnv([COUNTER], 3, backend=backend)
    else:
        envs = OctaxVectorEnv(COUNTER, 3, rom=counter_rom, backend=backend)
    envs.reset(seed=0)
    rewards = _refused(envs, _int64(kind, [2, value, 1]), rf"action {value} is out of range; valid actions are 0\.\.2")
    if rewards is not None:  # it ran: the bad row held no key (wrapped to 1, it would have scored 4)
        assert rewards.tolist() == [8.0, 0.0, 4.0]
    envs.reset(seed=0)
    assert np.asarray(envs.step(_int64(kind, [2, 1, 0]))[1]).tolist() == [8.0, 4.0, 0.0]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("value", BAD)
def test_the_multi_agent_env_refuses_an_out_of_range_action_of_any_width(two_counters_rom, backend, kind, value):
    from two_player_games import TWO_COUNTERS

    envs = octax_gym.MultiAgentVectorEnv(TWO_COUNTERS, 3, rom=two_counters_rom, backend=backend)
    envs.reset(seed=0)
    rewards = _refused(envs, _int64(kind, [[1, 0], [0, value], [2, 2]]),
                       rf"action {value} is out of range; valid actions are 0\.\.2 \(env 1, seat second_0")
    if rewards is not None:
        assert rewards.tolist() == [[4.0, 0.0], [0.0, 0.0], [8.0, 8.0]]
    envs.reset(seed=0)
    assert np.asarray(envs.step(_int64(kind, [[1, 0], [0, 1], [2, 2]]))[1]).tolist() == [[4, 0], [0, 4], [8, 8]]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("value", BAD)
def test_one_seat_against_an_opponent_refuses_an_out_of_range_action_of_any_width(two_counters_rom, backend, kind,
                                                                                  value):
    from two_player_games import TWO_COUNTERS

    envs = OctaxVectorEnv(TWO_COUNTERS, 3, rom=two_counters_rom, backend=backend, opponent="noop", seat=1)
    envs.reset(seed=0)
    rewards = _refused(envs, _int64(kind, [2, value, 1]), rf"action {value} is out of range; valid actions are 0\.\.2")
    if rewards is not None:
        assert rewards.tolist() == [8.0, 0.0, 4.0]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("kind", ("int",) + KINDS)
@pytest.mark.parametrize("value", BAD)
def test_the_single_env_refuses_an_out_of_range_action_of_any_width(counter_rom, backend, kind, value):
    env = octax_gym.OctaxEnv(COUNTER, rom=counter_rom, backend=backend)
    env.reset(seed=0)
    action = value if kind == "int" else _int64(kind, value)
    message = rf"^Counter: action {value} is out of range; valid actions are 0\.\.2$"
    with pytest.raises(InvalidActionError, match=message):
        env.step(action)
    assert env.step(2 if kind == "int" else _int64(kind, 2))[1] == 8.0


@pytest.mark.parametrize("kind", ("int",) + KINDS)
@pytest.mark.parametrize("value", BAD)
def test_pettingzoo_refuses_an_out_of_range_action_of_any_width(two_counters_rom, kind, value):
    pytest.importorskip("pettingzoo")
    from octax_gym import pettingzoo as octax_pz
    from two_player_games import TWO_COUNTERS

    env = octax_pz.parallel_env(TWO_COUNTERS, rom=two_counters_rom)
    env.reset(seed=0)
    action = value if kind == "int" else _int64(kind, value)
    with pytest.raises(InvalidActionError, match=rf"action {value} is out of range; valid actions are 0\.\.2 "
                                                 r"\(seat second_0\)$"):
        env.step({"first_0": 1, "second_0": action})
    _, rewards, *_ = env.step({"first_0": 1, "second_0": 2 if kind == "int" else _int64(kind, 2)})
    assert rewards == {"first_0": 4.0, "second_0": 8.0}


@pytest.mark.parametrize("dtype", ["uint32", "uint64"])
def test_unsigned_device_actions_are_named_by_their_value(make_envs, dtype):
    """uint32 2**32 - 1 once read as -1 (int32), and a torch uint64 has no clamp of its own."""
    torch = pytest.importorskip("torch", reason="the torch extra is installed by `make test`")
    envs = make_envs("torch")
    envs.reset(seed=0)
    with pytest.raises(InvalidActionError, match=rf"action {2**32 - 1} is out of range"):
        envs.step(torch.tensor([0, 2**32 - 1, 1], dtype=getattr(torch, dtype)))
        envs.close()
    envs.reset(seed=0)
    with pytest.raises(InvalidActionError, match=rf"action {2**32 - 1} is out of range"):
        envs.step(jnp.asarray([0, 2**32 - 1, 1], jnp.uint32))
        envs.close()


def test_the_first_bad_step_s_value_is_named_after_clean_ones(make_envs, monkeypatch):
    """Several steps pending: the error names the first bad action as given, not a later one's
    (accelerator tensors, stood in for as above, are checked on the device)."""
    torch = pytest.importorskip("torch", reason="the torch extra is installed by `make test`")
    monkeypatch.setattr("octax_gym.step.action_check._in_host_memory", lambda tensor: False)
    envs = make_envs("jax")
    envs.reset(seed=0)
    message = rf"action {2**40} is out of range; valid actions are 0\.\.2 \(env 1, "
    with pytest.raises(InvalidActionError, match=message):
        for actions in ([0, 1, 2], [0, 2**40, 0], [2**33, 0, 0], [0, 0, 0]):
            envs.step(torch.tensor(actions))  # may raise at a later step, once the report is ready
        envs.close()


def test_no_module_reaches_into_the_checks_private_helpers():
    """The envs use `to_device`, `to_int`, `check_batch` and `Turns`; the helpers behind them stay private."""
    package = Path(octax_gym.__file__).parent
    users = sorted(path.relative_to(package).as_posix() for path in package.rglob("*.py")
                   if "action_check._" in path.read_text())
    assert users == []
