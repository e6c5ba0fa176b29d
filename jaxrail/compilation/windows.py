"""A linear map of a table's window at run-time indices, one slice per batch member.

Under ``vmap`` a dynamic slice becomes a gather, and XLA:CPU's gather fetches element
by element with its index arithmetic: the contact table's windows (15 552 coefficients
for the trailer's 8 wheels) were the table-mode right-hand side's two largest kernels,
16 % of its traced time (docs/simulation.md, "The table's windows without a gather"). Stacking separate slices does not help: XLA fuses the
stack with the slices into one loop that picks its source element by element.

:func:`window_map` computes ``fn(lax.dynamic_slice(operand, starts, sizes), *args)``
for an ``fn`` linear in ``args`` (a weighted sum of the window). Its ``vmap`` over at
most :data:`UNROLLED` members (nested: the wheels of a wheelset, then the wheelsets),
with ``operand`` the same for all, evaluates it member by member: each slice copies its
window's contiguous rows and only ``fn``'s small results are stacked. Over more members
(a Monte Carlo batch) it is the gather again, so that a large batch does not unroll.
Derivatives are those of the plain expression (its tangent in ``args`` is ``fn`` of
theirs, linear; in ``operand``, the map of the operand's tangent; none in the integer
``starts``): they take the gather, the value alone does not.
"""

import functools

import jax
import jax.numpy as jnp
from jax.custom_batching import custom_vmap
from jax.custom_derivatives import SymbolicZero

UNROLLED = 8  # the most members of one vmap evaluated one by one


def _plain(fn, sizes, operand, starts, *args):
    window = jax.lax.dynamic_slice(operand, tuple(starts[i] for i in range(operand.ndim)),
                                   sizes)
    return fn(window, *args)


@functools.cache
def _window_map(fn, sizes):
    plain = functools.partial(_plain, fn, sizes)

    @custom_vmap
    def unrolled(operand, starts, *args):
        return plain(operand, starts, *args)

    @unrolled.def_vmap
    def _batched(axis_size, in_batched, operand, starts, *args):
        if not any(in_batched):
            return unrolled(operand, starts, *args), False
        if in_batched[0] or axis_size > UNROLLED:
            axes = tuple(0 if b else None for b in in_batched)
            return jax.vmap(plain, in_axes=axes)(operand, starts, *args), True
        def member(i):  # the i-th member's starts and args
            return [x[i] if b else x for x, b in zip((starts, *args), in_batched[1:])]

        return jnp.stack([unrolled(operand, *member(i)) for i in range(axis_size)]), True

    def jvp(primals, tangents):
        operand, starts, *args = primals
        out = unrolled(operand, starts, *args)
        zero = [isinstance(t, SymbolicZero) for t in tangents]
        terms = []
        if not all(zero[2:]):  # fn is linear in args: its tangent is fn of theirs
            dargs = [jnp.zeros(a.shape, a.dtype) if z else t
                     for a, t, z in zip(args, tangents[2:], zero[2:])]
            terms.append(plain(operand, starts, *dargs))
        if not zero[0]:
            terms.append(plain(tangents[0], starts, *args))
        return out, sum(terms) if terms else jnp.zeros_like(out)

    mapped = jax.custom_jvp(unrolled)
    mapped.defjvp(jvp, symbolic_zeros=True)
    return mapped


def window_map(fn, operand, starts, sizes, *args):
    """``fn(lax.dynamic_slice(operand, starts, sizes), *args)`` (module docstring):
    ``fn`` a module-level function linear in ``args`` (arrays); ``starts`` integer
    scalars, one per axis of ``operand`` (clamped as ``dynamic_slice`` clamps them);
    ``sizes`` static."""
    starts = jnp.stack([jnp.asarray(s, dtype=jnp.int32) for s in starts])
    return _window_map(fn, tuple(int(s) for s in sizes))(operand, starts, *args)
