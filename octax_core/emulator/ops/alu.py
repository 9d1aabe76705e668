"""Register arithmetic: 6XNN, 7XNN, 8XY0-8XYE, CXNN. Flags go in `vf`, applied after `vx`."""

from __future__ import annotations

import jax.numpy as jnp

from octax_core.emulator.ops import Context


def op_6xnn(c: Context) -> dict:
    """LD Vx, nn."""
    return {"vx": c.nn}


def op_7xnn(c: Context) -> dict:
    """ADD Vx, nn; no carry flag."""
    return {"vx": (c.vx + c.nn) & 0xFF}


def op_8xy0(c: Context) -> dict:
    """LD Vx, Vy."""
    return {"vx": c.vy}


def _logic(c: Context, value) -> dict:
    # COSMAC VIP's logic ops ran through a routine that clobbered VF.
    return {"vx": value, "vf": jnp.int32(0)} if c.quirks.vf_reset else {"vx": value}


def op_8xy1(c: Context) -> dict:
    """OR Vx, Vy; VF = 0 with vf_reset."""
    return _logic(c, c.vx | c.vy)


def op_8xy2(c: Context) -> dict:
    """AND Vx, Vy; VF = 0 with vf_reset."""
    return _logic(c, c.vx & c.vy)


def op_8xy3(c: Context) -> dict:
    """XOR Vx, Vy; VF = 0 with vf_reset."""
    return _logic(c, c.vx ^ c.vy)


def op_8xy4(c: Context) -> dict:
    """ADD Vx, Vy; VF = carry."""
    total = c.vx + c.vy
    return {"vx": total & 0xFF, "vf": (total >> 8).astype(jnp.int32)}


def op_8xy5(c: Context) -> dict:
    """SUB Vx, Vy; VF = 1 when there is no borrow."""
    return {"vx": (c.vx - c.vy) & 0xFF, "vf": (c.vx >= c.vy).astype(jnp.int32)}


def op_8xy7(c: Context) -> dict:
    """SUBN Vx, Vy: Vx = Vy - Vx; VF = 1 when there is no borrow."""
    return {"vx": (c.vy - c.vx) & 0xFF, "vf": (c.vy >= c.vx).astype(jnp.int32)}


def _shift_source(c: Context):
    return c.vy if c.quirks.shift_uses_vy else c.vx


def op_8xy6(c: Context) -> dict:
    """SHR Vx {, Vy}; VF = the bit shifted out."""
    source = _shift_source(c)
    return {"vx": source >> 1, "vf": source & 1}


def op_8xye(c: Context) -> dict:
    """SHL Vx {, Vy}; VF = the bit shifted out."""
    source = _shift_source(c)
    return {"vx": (source << 1) & 0xFF, "vf": source >> 7}


def xorshift32(r):
    """Marsaglia's xorshift32: three shifts, no threefry call per instruction."""
    r = r ^ (r << 13)
    r = r ^ (r >> 17)
    return r ^ (r << 5)


def op_cxnn(c: Context) -> dict:
    """RND Vx, nn: Vx = random byte AND nn."""
    rng = xorshift32(c.rng)
    return {"vx": (rng >> 24).astype(jnp.int32) & c.nn, "rng": rng}
