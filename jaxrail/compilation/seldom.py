"""A branch that a program seldom needs, computed only when some member of a batch
needs it.

``jnp.where(needed, rare(x), common(x))`` computes both branches for every element:
that is how vectorised code selects. Some branches are almost never taken: Hertz's
``e -> 1`` asymptote beyond ``|log(B/A)| = 32``, Kalker's coefficients beyond ``a/b``
of 0.1 to 10. They are also the costly ones, seven and six logarithms and exponentials
per contact patch, and with loops as kernels (:mod:`.loop_kernels`) XLA:CPU calls libm
once per element for each (docs/simulation.md, "Branches seldom taken").

:func:`seldom` computes ``fn(*operands)`` under a ``lax.cond`` on ``needed``. Under
``vmap`` (nested too: the patches of a wheel, the wheels, the wheelsets) the condition
becomes "any member needs it" and ``fn`` runs vmapped over the whole batch, or not at
all; a plain ``vmap`` of a ``cond`` would compute both branches. Where ``needed`` is
false the result is unspecified (zeros, or ``fn``'s value when another member needs
it): callers select it with ``needed``. Derivatives are ``fn``'s own, computed for
every member, as the plain expression's.

Only on the CPU: XLA:GPU reads a conditional's predicate back to the host before it
runs a branch, a synchronisation per evaluation, so there ``fn`` is computed for every
element as before (decided when the program is traced, for JAX's default backend).
"""

import functools

import jax
import jax.numpy as jnp
from jax.custom_batching import custom_vmap


def _zeros_like_output(fn, *operands):
    shapes = jax.eval_shape(fn, *operands)
    return jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype), shapes)


@functools.cache
def _seldom(fn):
    @custom_vmap
    def branch(needed, *operands):
        return jax.lax.cond(needed, fn, functools.partial(_zeros_like_output, fn), *operands)

    @branch.def_vmap
    def _batched(axis_size, in_batched, needed, *operands):
        axes = tuple(0 if b else None for b in in_batched[1:])
        batched = _vmapped(fn, axes, axis_size)
        any_needed = jnp.any(needed) if in_batched[0] else needed
        out = _seldom(batched)(any_needed, *operands)
        return out, jax.tree.map(lambda _: True, out)

    def jvp(primals, tangents):
        # fn's own value and tangent for every member (the plain expression's): the
        # tangent needs fn's value anyway, and reverse mode can transpose it
        return jax.jvp(fn, tuple(primals[1:]), tuple(tangents[1:]))

    wrapped = jax.custom_jvp(branch)
    wrapped.defjvp(jvp)
    return wrapped


@functools.cache
def _vmapped(fn, axes, axis_size):
    return jax.vmap(fn, in_axes=axes, axis_size=axis_size)


def seldom(fn, needed, *operands):
    """``fn(*operands)`` element by element where the boolean array ``needed`` holds,
    computed only when it holds for some element and some member of the enclosing
    ``vmap``s (module docstring); elsewhere unspecified. ``fn``: a module-level function
    of one element's operands (its identity keys a cache); ``operands``: arrays whose
    leading axes are ``needed``'s shape, followed by one element's. Each output has
    ``needed``'s shape followed by its shape for one element."""
    shape = jnp.shape(needed)
    needed = jnp.asarray(needed, dtype=bool).reshape(-1)
    flat = [jnp.reshape(x, (-1,) + jnp.shape(x)[len(shape):]) for x in operands]
    if jax.default_backend() == "cpu":
        out = jax.vmap(_seldom(fn))(needed, *flat)
    else:
        out = jax.vmap(fn)(*flat)
    return jax.tree.map(lambda x: x.reshape(shape + x.shape[1:]), out)
