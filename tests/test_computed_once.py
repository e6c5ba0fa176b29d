"""``computed_once``: the values unchanged (under jit, vmap and grad, gradients against
central differences), and a value read by two kernels computed once in the optimised
program instead of in each."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxrail._hlo_operations import element_counts
from jaxrail.compilation import computed_once


def _chain(x):
    """Cheap elementwise work, as a force law's: XLA fuses it into its consumers."""
    y = x
    for k in range(12):
        y = y * (1.0 + 0.01 * k) + 0.1 * x
    return y


def test_values_are_unchanged_bit_for_bit():
    x = jnp.linspace(-2.0, 3.0, 7)
    parts = (jnp.sin(x), x ** 2, jnp.exp(-x))
    for out, part in zip(jax.jit(computed_once)(*parts), parts):
        np.testing.assert_array_equal(out, part)
    rows = jnp.stack(parts, axis=-1)  # one array: its last axis
    np.testing.assert_array_equal(jax.jit(computed_once)(rows), rows)
    batched = jax.vmap(lambda a, b: computed_once(a, b))(rows[:, 0], rows[:, 1])
    np.testing.assert_array_equal(batched[0], rows[:, 0])


def test_gradient_against_central_differences():
    def f(x):
        a, b = computed_once(jnp.sin(x) * x, jnp.cos(x))
        return jnp.sum(a * b + a ** 2)

    x = jnp.array([0.3, -1.2, 2.0])
    grad = jax.grad(f)(x)
    step = 1e-6
    for i in range(x.size):
        e = jnp.zeros_like(x).at[i].set(step)
        np.testing.assert_allclose(grad[i], (f(x + e) - f(x - e)) / (2 * step), rtol=1e-7)
    np.testing.assert_allclose(jax.jacfwd(f)(x), grad, rtol=1e-14)


def _arithmetic(function, *args):
    return element_counts(jax.jit(function).lower(*args).compile())["arithmetic"]


def test_a_value_read_by_two_kernels_is_computed_once():
    x, z = jnp.linspace(0.0, 1.0, 16), jnp.linspace(1.0, 2.0, 32)

    def copied(x, z):  # the sum and the outer product each compute the chain
        y = _chain(x)
        return jnp.sum(y), y[:, None] * z[None, :]

    def once(x, z):
        y, _ = computed_once(_chain(x), x)
        return jnp.sum(y), y[:, None] * z[None, :]

    np.testing.assert_array_equal(jax.jit(once)(x, z)[1], jax.jit(copied)(x, z)[1])
    chain = 2 * 12 * x.size  # the chain's multiplies and adds, once
    product = x.size * z.size
    # copied: the chain in the sum's kernel and again in the product's
    assert _arithmetic(copied, x, z) >= 2 * chain + product
    # once: the chain, its product with the (2, 2) identity, the sum and the product
    assert _arithmetic(once, x, z) <= chain + 2 * 2 * x.size + x.size + product + 0.1 * chain
