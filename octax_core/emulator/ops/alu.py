"""Register arithmetic: 6XNN, 7XNN, 8XY0-8XYE, CXNN. Flags go in `vf`, applied after `vx`."""

from __future__ import annotations

import jax.numpy as jnp

from octax_core.emulator.ops import Context, Effect
from octax_core.emulator.quirks import choose


def op_6xnn(c: Context) -> Effect:
    """LD Vx, nn."""
    return Effect(vx=c.nn)


def op_7xnn(c: Context) -> Effect:
    """ADD Vx, nn; no carry flag."""
    return Effect(vx=(c.vx + c.nn) & 0xFF)


def op_8xy0(c: Context) -> Effect:
    """LD Vx, Vy."""
    return Effect(vx=c.vy)


def _logic(c: Context, value) -> Effect:
    # COSMAC VIP's logic ops ran through a routine that clobbered VF.
    if isinstance(c.quirks.vf_reset, bool):
        return Effect(vx=value, vf=jnp.int32(0)) if c.quirks.vf_reset else Effect(vx=value)
    # A mix of profiles: VF is written either way, with what it holds after Vx is written.
    unchanged = jnp.where(c.x == 0xF, value, c.V[0xF])
    return Effect(vx=value, vf=jnp.where(c.quirks.vf_reset, 0, unchanged).astype(jnp.int32))


def op_8xy1(c: Context) -> Effect:
    """OR Vx, Vy; VF = 0 with vf_reset."""
    return _logic(c, c.vx | c.vy)


def op_8xy2(c: Context) -> Effect:
    """AND Vx, Vy; VF = 0 with vf_reset."""
    return _logic(c, c.vx & c.vy)


def op_8xy3(c: Context) -> Effect:
    """XOR Vx, Vy; VF = 0 with vf_reset."""
    return _logic(c, c.vx ^ c.vy)


def op_8xy4(c: Context) -> Effect:
    """ADD Vx, Vy; VF = carry."""
    total = c.vx + c.vy
    return Effect(vx=total & 0xFF, vf=(total >> 8).astype(jnp.int32))


def op_8xy5(c: Context) -> Effect:
    """SUB Vx, Vy; VF = 1 when there is no borrow."""
    return Effect(vx=(c.vx - c.vy) & 0xFF, vf=(c.vx >= c.vy).astype(jnp.int32))


def op_8xy7(c: Context) -> Effect:
    """SUBN Vx, Vy: Vx = Vy - Vx; VF = 1 when there is no borrow."""
    return Effect(vx=(c.vy - c.vx) & 0xFF, vf=(c.vy >= c.vx).astype(jnp.int32))


def _shift_source(c: Context):
    return choose(c.quirks.shift_uses_vy, c.vy, c.vx)


def op_8xy6(c: Context) -> Effect:
    """SHR Vx {, Vy}; VF = the bit shifted out."""
    source = _shift_source(c)
    return Effect(vx=source >> 1, vf=source & 1)


def op_8xye(c: Context) -> Effect:
    """SHL Vx {, Vy}; VF = the bit shifted out."""
    source = _shift_source(c)
    return Effect(vx=(source << 1) & 0xFF, vf=source >> 7)


def xorshift32(r):
    """Marsaglia's xorshift32: three shifts, no threefry call per instruction."""
    r = r ^ (r << 13)
    r = r ^ (r >> 17)
    return r ^ (r << 5)


def op_cxnn(c: Context) -> Effect:
    """RND Vx, nn: Vx = random byte AND nn."""
    rng = xorshift32(c.rng)
    return Effect(vx=(rng >> 24).astype(jnp.int32) & c.nn, rng=rng)
