"""``window_map``: the plain expression ``fn(dynamic_slice(...), *args)``'s values under
jit and nested vmap (unrolled, and a batch too large to unroll), its derivatives in the
arguments and the operand against central differences and the plain expression's, and
no gather in a nested vmap's optimised program (one slice per member)."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxrail.compilation.windows import UNROLLED, window_map

SIZES = (2, 3, 4)


def _weighted(window, weight):
    """(2, 4): the window (2, 3, 4) summed over its middle axis with weights (3,)."""
    return jnp.einsum("n,lnf->lf", weight, window)


def _plain(operand, starts, weight):
    window = jax.lax.dynamic_slice(operand, tuple(starts), SIZES)
    return _weighted(window, weight)


def _mapped(operand, starts, weight):
    return window_map(_weighted, operand, tuple(starts), SIZES, weight)


def _data(members):
    rng = np.random.default_rng(3)
    operand = jnp.asarray(rng.normal(size=(5, 9, 7)))
    # the last start is beyond the axis for some members: clamped as dynamic_slice clamps
    starts = jnp.asarray(rng.integers(0, [4, 7, 6], size=(*members, 3)), dtype=jnp.int32)
    weights = jnp.asarray(rng.normal(size=(*members, 3)))
    return operand, starts, weights


def _nested(function):
    return jax.vmap(jax.vmap(function, in_axes=(None, 0, 0)), in_axes=(None, 0, 0))


def test_values_under_jit_and_nested_vmap_equal_the_plain_expression():
    operand, starts, weights = _data((4, 2))
    out = jax.jit(_nested(_mapped))(operand, starts, weights)
    np.testing.assert_array_equal(out, _nested(_plain)(operand, starts, weights))
    np.testing.assert_array_equal(jax.jit(_mapped)(operand, starts[0, 0], weights[0, 0]),
                                  _plain(operand, starts[0, 0], weights[0, 0]))
    big = _data((UNROLLED + 3,))  # too many members to unroll: the gather
    batched = jax.vmap(_mapped, in_axes=(None, 0, 0))
    np.testing.assert_array_equal(jax.jit(batched)(*big),
                                  jax.vmap(_plain, in_axes=(None, 0, 0))(*big))


def test_a_nested_vmap_slices_each_member_and_gathers_nothing():
    operand, starts, weights = _data((4, 2))
    text = jax.jit(_nested(_mapped)).lower(operand, starts, weights).compile().as_text()
    assert " gather(" not in text
    assert text.count(" dynamic-slice(") == 8
    plain = jax.jit(_nested(_plain)).lower(operand, starts, weights).compile().as_text()
    assert " gather(" in plain


def test_derivatives_against_central_differences_and_the_plain_expression():
    operand, starts, weights = _data((4, 2))
    probe = jnp.asarray(np.random.default_rng(5).normal(size=(4, 2, 2, 4)))

    def loss(function, w, scale):
        return jnp.sum(probe * jnp.sin(_nested(function)(operand * scale, starts, w)))

    for argnums in (0, 1):
        args = (weights, 1.3)
        grad = jax.jit(jax.grad(lambda *a: loss(_mapped, *a), argnums=argnums))(*args)
        forward = jax.jacfwd(lambda *a: loss(_mapped, *a), argnums=argnums)(*args)
        plain = jax.grad(lambda *a: loss(_plain, *a), argnums=argnums)(*args)
        np.testing.assert_allclose(grad, plain, rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(forward, plain, rtol=1e-13, atol=1e-14)
    h = 1e-6
    e = jnp.zeros_like(weights).at[1, 0, 2].set(h)
    central = (loss(_plain, weights + e, 1.3) - loss(_plain, weights - e, 1.3)) / (2 * h)
    grad = jax.grad(lambda w: loss(_mapped, w, 1.3))(weights)
    np.testing.assert_allclose(grad[1, 0, 2], central, rtol=1e-7)
    central = (loss(_plain, weights, 1.3 + h) - loss(_plain, weights, 1.3 - h)) / (2 * h)
    np.testing.assert_allclose(jax.grad(lambda s: loss(_mapped, weights, s))(1.3), central,
                               rtol=1e-7)
