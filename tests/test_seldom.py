"""``seldom``: a branch computed only where some member of a batch needs it. Its values
equal the plain expression's where needed, under jit, nested vmap and a large batch;
the branch is a conditional on one predicate for the whole nested batch; derivatives
match the plain expression's and central differences."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxrail.compilation.seldom import seldom


def _rare(x, y):
    """A branch with transcendental functions and two outputs of different shapes."""
    return jnp.log(x) * y, jnp.stack([jnp.exp(-x), jnp.arctan(x * y)])


def _selected(x, y):
    """The caller's pattern: the branch where x > 2, a cheap value elsewhere."""
    needed = x > 2.0
    a, b = seldom(_rare, needed, x, y)
    return jnp.where(needed, a, -x), jnp.where(needed, b, jnp.stack([x, y]))


def _plain(x, y):
    a, b = _rare(x, y)
    needed = x > 2.0
    return jnp.where(needed, a, -x), jnp.where(needed, b, jnp.stack([x, y]))


def _nested(function):
    return jax.vmap(jax.vmap(function, in_axes=(0, None)), in_axes=(0, None))


def _close(got, want):
    for g, w in zip(jax.tree.leaves(got), jax.tree.leaves(want)):
        np.testing.assert_allclose(g, w, rtol=1e-15, atol=0.0)


def test_values_equal_the_plain_expression_under_jit_and_nested_vmap():
    x = jnp.linspace(0.5, 3.5, 8).reshape(4, 2)
    _close(jax.jit(_nested(_selected))(x, 0.7), _nested(_plain)(x, 0.7))
    none_needed = x - 2.0  # all below 2: the branch is skipped, the selection holds
    _close(jax.jit(_nested(_selected))(none_needed, 0.7), _nested(_plain)(none_needed, 0.7))
    _close(jax.jit(_selected)(jnp.float64(3.0), 0.7), _plain(jnp.float64(3.0), 0.7))
    _close(jax.jit(_selected)(jnp.float64(1.0), 0.7), _plain(jnp.float64(1.0), 0.7))
    many = jnp.linspace(0.0, 4.0, 23)  # a batch of any size, batched in both operands
    _close(jax.jit(jax.vmap(_selected))(many, many), jax.vmap(_plain)(many, many))


def test_arrays_are_taken_element_by_element():
    x = jnp.linspace(1.5, 2.5, 6).reshape(2, 3)
    a, b = seldom(_rare, x > 2.0, x, jnp.full((2, 3), 0.7))
    assert a.shape == (2, 3) and b.shape == (2, 3, 2)
    want_a, want_b = jax.vmap(jax.vmap(_rare))(x, jnp.full((2, 3), 0.7))
    needed = np.asarray(x > 2.0)
    np.testing.assert_allclose(np.asarray(a)[needed], np.asarray(want_a)[needed], rtol=1e-15)
    np.testing.assert_allclose(np.asarray(b)[needed], np.asarray(want_b)[needed], rtol=1e-15)


def _conditionals(jaxpr):
    """Predicate shapes of every cond in a closed jaxpr, nested ones included."""
    found = []
    for equation in jaxpr.eqns:
        if equation.primitive.name == "cond":
            found.append(equation.invars[0].aval.shape)
        for value in equation.params.values():
            inner = getattr(value, "jaxpr", None)
            if inner is not None:
                found += _conditionals(getattr(inner, "jaxpr", inner))
    return found


def test_a_nested_batch_takes_one_conditional_and_no_select_between_branches():
    x = jnp.linspace(0.5, 3.5, 8).reshape(4, 2)
    jaxpr = jax.make_jaxpr(_nested(_selected))(x, 0.7).jaxpr
    assert _conditionals(jaxpr) == [()]  # one scalar predicate: "any member needs it"
    plain = jax.make_jaxpr(_nested(lambda x, y: jax.lax.cond(x > 2.0, _rare, _rare, x, y)))(
        x, 0.7).jaxpr
    assert _conditionals(plain) == []  # a vmapped cond turns into a select of both


def test_derivatives_equal_the_plain_expressions_and_central_differences():
    x = jnp.array([1.2, 2.5, 3.1])

    def total(function, x, y):
        a, b = jax.vmap(function, in_axes=(0, None))(x, y)
        return jnp.sum(a) + jnp.sum(b ** 2)

    for y in (0.7, -1.3):
        grad = jax.jit(jax.grad(total, argnums=(1, 2)), static_argnums=0)(_selected, x, y)
        plain = jax.grad(total, argnums=(1, 2))(_plain, x, y)
        _close(grad, plain)
        forward = jax.jacfwd(total, argnums=2)(_selected, x, y)
        np.testing.assert_allclose(forward, plain[1], rtol=1e-14)
        h = 1e-6
        for k in range(3):
            step = jnp.zeros(3).at[k].set(h)
            central = (total(_plain, x + step, y) - total(_plain, x - step, y)) / (2 * h)
            np.testing.assert_allclose(grad[0][k], central, rtol=1e-7)
        central = (total(_plain, x, y + h) - total(_plain, x, y - h)) / (2 * h)
        np.testing.assert_allclose(grad[1], central, rtol=1e-7)


def test_other_backends_compute_the_branch_for_every_element(monkeypatch):
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    x = jnp.linspace(0.5, 3.5, 8).reshape(4, 2)
    jaxpr = jax.make_jaxpr(_nested(_selected))(x, 0.7).jaxpr
    assert _conditionals(jaxpr) == []
    _close(jax.jit(_nested(_selected))(x, 0.7), _nested(_plain)(x, 0.7))
