"""A part of a computation that only some evaluations need."""

import jax
import jax.numpy as jnp


def zeros_of(shapes):
    """Zeros (of each leaf's dtype) shaped as the pytree ``shapes`` (arrays or
    ``jax.ShapeDtypeStruct``s, e.g. from ``jax.eval_shape``)."""
    return jax.tree.map(lambda x: jnp.zeros(x.shape, x.dtype), shapes)


def computed_when(flag, function):
    """``function()`` where ``flag`` holds, zeros of its shapes elsewhere.

    ``flag``: a Python bool (then ``function`` is called or not, as written), a traced
    scalar bool (then one ``lax.cond``, so that a loop whose first iteration alone needs
    the part holds it once and runs it once), or a tuple of them, all of which must hold,
    tested one inside the other in order. Under ``vmap`` a ``lax.cond`` on a batched flag
    runs both branches; a loop's own counter stays unbatched, so it goes first."""
    if isinstance(flag, tuple):
        if not flag:
            return function()
        return computed_when(flag[0], lambda: computed_when(flag[1:], function))
    if flag is True:
        return function()
    zeros = lambda: zeros_of(jax.eval_shape(function))  # noqa: E731
    if flag is False:
        return zeros()
    return jax.lax.cond(flag, function, zeros)
