"""`when_any`: work that only a few machines of a batch need, skipped when none of them does.

Under `vmap` there is no branching: a `lax.cond` on a per-machine predicate becomes a select, and
every machine pays for both branches on every instruction. Most of an instruction's expensive
work is needed by few machines at a time (a hires sprite, a scroll, a memory write), so the
batch asks once, "does any machine need it?", and runs the work for the whole batch, or not at
all. `jax.custom_batching.custom_vmap` gives `when_any` that batched shape; one machine alone
gets a plain `lax.cond`.

The contract that keeps it exact: `fn(operands)` must give back `operands` unchanged, bit for
bit, on a machine whose predicate is false. Then running it for the whole batch, or skipping
it, changes nothing for any machine, and no select over the (large) operands is needed.

The skip pays on a CPU, where the batch's work is the time. On a GPU the loop's predicate is read
back to the host before each trip (a device-to-host sync; an instruction has two gates, the memory
write and the rare work, and four more inside the second), which cost more than the work it
skips: there the work simply runs for the whole batch, which the contract makes the same.
`LOOPED_PLATFORMS` names where the gate loops; `jax.lax.platform_dependent` picks per platform
when the program is lowered, so one traced program serves both (on a host whose backends are all
of one kind, only that kind's form is traced); `where_looped` makes the same
choice for work around a gate (`cpu._draw` reads plane 1's collision before the rare work where
the gate loops, after it elsewhere).
"""

from __future__ import annotations

from typing import Callable, TypeVar

import jax
import jax.numpy as jnp

T = TypeVar("T")

# Platforms where a batch skips the gated work when no machine needs it; elsewhere it always runs.
LOOPED_PLATFORMS: tuple[str, ...] = ("cpu",)


def when_any(pred: jax.Array, fn: Callable[[T, object], T], operands: T, inputs=()) -> T:
    """`fn(operands, inputs)` when `pred` holds for any machine of the batch, else `operands`.

    Args:
        pred: bool scalar for one machine (a batch of them under `vmap`).
        fn: one machine's work; a no-op (bit for bit) on a machine whose `pred` is false. It
            must read nothing but its arguments (no closed-over traced values).
        operands: a pytree, returned with the same structure, shapes and dtypes.
        inputs: a pytree `fn` reads and does not return.
    """

    @jax.custom_batching.custom_vmap
    def gated(pred, operands, inputs):
        return _per_platform(pred, fn, operands, inputs)

    @gated.def_vmap
    def gated_batched(axis_size, in_batched, pred, operands, inputs):
        pred_batched, operands_batched, inputs_batched = in_batched
        operands, inputs = (_batch(tree, batched, axis_size)
                            for tree, batched in ((operands, operands_batched), (inputs, inputs_batched)))
        anyone = jnp.any(pred) if pred_batched else pred
        out = _per_platform(anyone, jax.vmap(fn), operands, inputs)
        return out, jax.tree.map(lambda _: True, out)

    return gated(pred, operands, inputs)


def any_of_batch(*preds: jax.Array) -> tuple[jax.Array, ...]:
    """For each per-machine predicate, whether it holds for some machine of the batch: one
    reduction for them all, where a `when_any` per predicate reduces its own (each reduction is
    a few XLA kernels, paid on every instruction). One machine alone gets its predicates back.

    A `when_any` given the result runs its work for the whole batch when some machine needs it,
    as with the per-machine predicate: the contract (a no-op for a machine that does not need
    it) is what keeps that exact."""

    @jax.custom_batching.custom_vmap
    def each(preds):
        return preds

    @each.def_vmap
    def each_batched(axis_size, in_batched, preds):
        # A predicate the batch shares is broadcast: any of its copies is itself.
        stacked = jnp.stack([jnp.broadcast_to(p, (axis_size,)) for p in preds], axis=1)
        return tuple(jnp.any(stacked, axis=0)), tuple(False for _ in preds)

    return each(tuple(jnp.asarray(p, jnp.bool_) for p in preds))


def where_looped(looped: Callable, always: Callable, *args):
    """`looped(*args)` in a program lowered for one of `LOOPED_PLATFORMS`, `always(*args)`
    elsewhere: for work around a gate whose best form depends on whether the gate is a loop (the
    two must give the same result; `jax.lax.platform_dependent` picks when the program is
    lowered, so one traced program serves every platform)."""
    if not LOOPED_PLATFORMS:
        return always(*args)
    only = _only_backends()
    if only is not None and only <= set(LOOPED_PLATFORMS):
        return looped(*args)
    if only is not None and not only & set(LOOPED_PLATFORMS):
        return always(*args)
    return jax.lax.platform_dependent(*args, default=always, **{platform: looped for platform in LOOPED_PLATFORMS})


def _only_backends():
    """The platforms this process can lower programs for, or None before JAX's backends start.

    When every backend is of one kind (a CPU-only host: the tests, most users' laptops), the
    program can only ever be lowered for it, so `where_looped` traces the one branch that lowering
    would pick. `platform_dependent` traces every branch, and the gates nest (an instruction's rare
    work holds four more), so on a CPU-only host this halves an XO-CHIP machine's trace, for the
    same lowered program."""
    from jax._src import xla_bridge

    if not xla_bridge.backends_are_initialized():
        return None
    return {backend.platform for backend in xla_bridge.backends().values()}


def _per_platform(pred, fn, operands, inputs):
    """The loop of `_at_most_once` on `LOOPED_PLATFORMS`, `fn` unconditionally elsewhere."""
    return where_looped(lambda pred, operands, inputs: _at_most_once(pred, fn, operands, inputs),
                        lambda pred, operands, inputs: fn(operands, inputs), pred, operands, inputs)


def _at_most_once(pred, fn, operands, inputs):
    """`fn(operands, inputs)` if `pred`, else `operands`, as a loop that runs zero times or once.

    Not a `lax.cond`: XLA:CPU copies a conditional's operands that its skipping branch hands
    straight back (a whole screen per instruction, measured), where a loop's carry is updated
    in place, and when the loop does not run, nothing is copied or computed."""
    def body(carry):
        again, operands = carry
        # `again & False`, not a constant: under `shard_map` the predicate varies over the mesh,
        # and a loop's carry must keep its type
        return again & False, fn(operands, inputs)

    _, out = jax.lax.while_loop(lambda carry: carry[0], body, (jnp.asarray(pred, jnp.bool_), operands))
    return out


def _batch(tree, batched, axis_size: int):
    """Gives every unbatched leaf of `tree` a leading axis of `axis_size`."""
    return jax.tree.map(lambda leaf, b: leaf if b else jnp.broadcast_to(leaf, (axis_size, *jnp.shape(leaf))),
                        tree, batched)
