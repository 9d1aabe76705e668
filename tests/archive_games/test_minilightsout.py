"""Mini Lights Out: a solver wins every puzzle, random pressing runs out of moves."""

import jax.numpy as jnp
import numpy as np

from archive_play import play
from octax_core.emulator.state import NO_KEY, unpack_screen

KEY_WAIT_PC = 0x2F0  # `game-loop`: v3 := key


def _toggles() -> np.ndarray:
    """A[i, j] = 1 where pressing light j toggles light i: itself and its torus neighbours."""
    A = np.zeros((16, 16), np.int64)
    for r in range(4):
        for c in range(4):
            for dr, dc in ((0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)):
                A[4 * ((r + dr) % 4) + (c + dc) % 4, 4 * r + c] = 1
    return A


def _inverse_gf2(A: np.ndarray) -> np.ndarray:
    n = len(A)
    M = np.concatenate([A % 2, np.eye(n, dtype=np.int64)], axis=1)
    for col in range(n):
        pivot = next(r for r in range(col, n) if M[r, col])  # StopIteration: not invertible
        M[[col, pivot]] = M[[pivot, col]]
        for r in range(n):
            if r != col and M[r, col]:
                M[r] ^= M[col]
    return M[:, n:]


A_INV = _inverse_gf2(_toggles())


def _lit(machine):
    """The 16 lights, row-major, 1 = on: the pixel the ROM's `test` sprite probes (top-right of
    the cell) is dark for an 'on' light (a filled 6x6 square), lit for an 'off' one (a frame)."""
    pixels = unpack_screen(machine.screen, on=1, dtype=jnp.int32)
    return jnp.stack([1 - pixels[8 * r, 16 + 8 * c + 7] for r in range(4) for c in range(4)])


def _press_when_asked(choose):
    """Presses `choose(lit lights)`'s light while `game-loop` waits with no key seen, else no-op
    (which releases a held key: FX0A completes on release)."""
    def policy(state, key):
        machine = state.machine
        asking = (machine.pc == KEY_WAIT_PC) & (machine.key_wait == NO_KEY)
        return jnp.where(asking, 1 + choose(_lit(machine), key), 0)
    return policy


def _solve(lit, key):
    """A lit light of the solution (A^-1 lit over GF(2)), or any lit light if none is."""
    solution = (jnp.asarray(A_INV) @ lit) % 2
    useful = solution * lit
    return jnp.where(useful.any(), jnp.argmax(useful), jnp.argmax(lit))


def test_the_toggle_matrix_is_invertible_and_lights_read_right():
    assert ((_toggles() @ A_INV) % 2 == np.eye(16)).all()
    from octax_core.env import make
    import jax
    env, params = make("MiniLightsOut")
    _, state = env.reset(jax.random.key(3), params)
    _, other = env.reset(jax.random.key(4), params)
    step = jax.jit(env.step)
    for _ in range(30):  # `init-game` draws the grid
        _, state, *_ = step(jax.random.key(0), state, 0, params)
        _, other, *_ = step(jax.random.key(0), other, 0, params)
    lit, lit_other = np.asarray(_lit(state.machine)), np.asarray(_lit(other.machine))
    assert 0 < lit.sum() < 16 and (lit != lit_other).any()  # the puzzle is the reset key's
    assert int(state.machine.pc) == KEY_WAIT_PC and not bool(state.done)


def test_a_solver_wins_every_puzzle():
    played = play("MiniLightsOut", _press_when_asked(_solve), steps=500, num_envs=2)
    assert played.episodes_ended >= 4
    assert set(np.unique(played.rewards)) == {0.0, 1.0}
    ends = played.terminated
    assert (played.rewards[ends] == 1).all() and played.rewards[~ends].sum() == 0  # the win is the end


def _random_lit(lit, key):
    import jax
    return jax.random.categorical(key, jnp.where(lit == 1, 0.0, -jnp.inf))


def test_random_play_runs_out_of_moves():
    """Random presses of lit lights: the 100th move (`steps` VD = 100) ends the game unsolved."""
    played = play("MiniLightsOut", _press_when_asked(_random_lit), steps=800, num_envs=2)
    assert played.episodes_ended >= 2
    assert played.rewards.sum() < played.episodes_ended  # mostly losses: an end without a reward
    assert ((played.rewards == 0) | (played.rewards == 1)).all()
    assert played.rewards[~played.terminated].sum() == 0
