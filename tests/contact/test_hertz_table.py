"""The tabulated Hertz coefficients (the default, ``method="table"``) against the exact
path (Newton solve with elliptic integrals, tested in test_hertz.py): accuracy on a
dense sample, the asymptote beyond the table, symmetry, smoothness through the sphere,
gradients against central differences, zero load, jit/vmap, no work at import."""

import importlib
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact.hertz import hertz, hertz_coefficients, hertz_from_curvatures

hertz_module = importlib.import_module("jaxrail.contact.hertz")

G_STEEL, NU_STEEL = 8.2e10, 0.28
TABLE_TOL = 1e-9  # measured: 3e-11 relative in every field (the requirement is 1e-6)
COEFFS = ("m", "n", "r", "a_over_c0", "b_over_c0", "stiffness_factor")
N_SAMPLE = 8192


def _coefficients(t, method):
    c = hertz_module._coefficients_of_t(t, method)
    return jnp.stack([getattr(c, f) for f in COEFFS])


_batch = {m: jax.jit(lambda t, m=m: _coefficients(t, m)) for m in ("table", "exact")}


def _fields(c):
    return jnp.stack([c.a, c.b, c.approach, c.stiffness, c.p0], axis=-1)


def _hertz_table(n, a, b):
    return _fields(hertz(n, a, b, G_STEEL, NU_STEEL))


_jac = jax.jit(jax.vmap(jax.jacfwd(_hertz_table, argnums=(0, 1, 2))))
_jac_rev = jax.jit(jax.vmap(jax.jacrev(_hertz_table, argnums=(0, 1, 2))))
_value = jax.jit(jax.vmap(_hertz_table))


def _sample():
    rng = np.random.default_rng(19)
    return np.concatenate(
        [
            rng.uniform(-45.0, 45.0, N_SAMPLE // 4),  # past the table's |t| <= 32
            rng.uniform(np.log(0.3), np.log(1e4), N_SAMPLE // 4),  # the wheel-rail range
            rng.uniform(-0.5, 0.5, N_SAMPLE // 4),  # around the sphere
            np.linspace(-33.0, 33.0, N_SAMPLE // 4),  # through every table interval
        ]
    )


def test_table_matches_exact_on_a_dense_sample():
    t = _sample()
    table = np.asarray(_batch["table"](t))
    exact = np.asarray(_batch["exact"](t))
    rel = np.abs(table / exact - 1.0)
    assert np.all(np.isfinite(table))
    assert np.max(rel) < TABLE_TOL, dict(zip(COEFFS, np.max(rel, axis=1)))


def test_sphere_and_table_ends():
    t = np.array([0.0, -32.0, 32.0, -32.0 - 1e-9, 32.0 + 1e-9, 1e-300])
    table = np.asarray(_batch["table"](np.resize(t, N_SAMPLE)))[:, : t.size]
    exact = np.asarray(_batch["exact"](np.resize(t, N_SAMPLE)))[:, : t.size]
    np.testing.assert_allclose(table, exact, rtol=1e-13)  # nodes and the asymptote
    np.testing.assert_array_equal(table[:, 0], table[:, 5])  # no kink of the lookup at 0
    # at the sphere: a = b = c0, r = 1, K_H = (4/3) E* sqrt(R) in units of E*
    np.testing.assert_allclose(table[:, 0], [1, 1, 1, 1, 1, 4 / 3], rtol=1e-14)


def test_odd_and_even_in_t():
    t = _sample()
    plus = np.asarray(_batch["table"](t))
    minus = np.asarray(_batch["table"](-t))
    m, n, r, a, b, k = range(6)
    np.testing.assert_allclose(plus[[m, n, r, k]], minus[[m, n, r, k]], rtol=1e-14)
    np.testing.assert_allclose(plus[a], minus[b], rtol=1e-14)


@pytest.mark.parametrize(
    "point",
    [
        (5e4, 1.087, 1.087 * (1 + 1e-9)),  # next to the sphere
        (5e4, 1.0, 1.0),  # the sphere exactly (a table node)
        (5e4, 1.087, 1.667),
        (2e3, 4.0, 1.3),  # A > B
        (1e5, 1.087, 0.3 * 1.087),  # the wheel-rail floor B/A = 0.3
        (1e5, 0.5, 5e3),  # flange-like, B/A = 1e4
        (1e5, 1.0, 1e15),  # past the table (asymptote)
    ],
)
def test_gradients_vs_central_differences(point):
    args = [np.full(2, x) for x in point]
    ad = np.stack([np.asarray(j)[0] for j in _jac(*args)], axis=-1)  # (field, argument)
    rev = np.stack([np.asarray(j)[0] for j in _jac_rev(*args)], axis=-1)
    np.testing.assert_allclose(rev, ad, rtol=1e-12, atol=1e-12 * np.max(np.abs(ad)))
    fd = np.zeros_like(ad)
    for i in range(3):
        h = 1e-6 * point[i]
        plus, minus = list(point), list(point)
        plus[i] += h
        minus[i] -= h
        both = np.asarray(_value(*[np.array([p, q]) for p, q in zip(plus, minus)]))
        fd[:, i] = (both[0] - both[1]) / (2 * h)
    scale = np.max(np.abs(ad), axis=1, keepdims=True)
    np.testing.assert_allclose(ad / scale, fd / scale, atol=1e-6)


def test_gradient_matches_exact_and_is_continuous_at_the_sphere():
    # d log(a/b) / d log(B/A) -> 2/3 at the sphere, from both sides and exactly at it.
    def log_ab(t, method):
        c = hertz_module._coefficients_of_t(t, method)
        return jnp.log(c.a_over_c0 / c.b_over_c0)

    t = np.array([-1e-3, -1e-9, 0.0, 1e-9, 1e-3, 0.7, -3.0, 6.9])
    slopes = {
        m: np.asarray(jax.jit(jax.vmap(jax.grad(lambda x, m=m: log_ab(x, m))))(t))
        for m in ("table", "exact")
    }
    np.testing.assert_allclose(slopes["table"], slopes["exact"], rtol=1e-8)
    np.testing.assert_allclose(slopes["table"][1:4], 2 / 3, rtol=1e-8)


def test_zero_load_and_sphere_are_finite():
    n = np.array([0.0, -5.0, 0.0, 3e4])
    a = np.array([1.0, 1.0, 2.0, 1.0])
    b = np.array([1.0, 3.0, 2.0, 1e20])
    out = np.asarray(_value(n, a, b))
    assert np.all(np.isfinite(out))
    np.testing.assert_array_equal(out[:3, [0, 1, 2, 4]], 0.0)
    for j in list(_jac(n, a, b)) + list(_jac_rev(n, a, b)):
        assert np.all(np.isfinite(np.asarray(j)))


def test_default_is_the_table_and_methods_agree():
    n, r, kw, kr = 5e4, 0.46, -1 / 0.5, 1 / 0.3
    default = _fields(hertz_from_curvatures(n, r, kw, kr, min_curvature_ratio=0.3))
    table = _fields(hertz_from_curvatures(n, r, kw, kr, min_curvature_ratio=0.3, method="table"))
    exact = _fields(hertz_from_curvatures(n, r, kw, kr, min_curvature_ratio=0.3, method="exact"))
    np.testing.assert_array_equal(default, table)
    np.testing.assert_allclose(table, exact, rtol=TABLE_TOL)
    c = hertz_coefficients(np.array([1.0, 2.0]), np.array([3.0, 2.0]))  # broadcasting
    assert c.m.shape == (2,)
    with pytest.raises(ValueError, match="method"):
        hertz(1e4, 1.0, 1.0, method="spline")


def test_no_table_and_no_xla_at_import():
    code = (
        "import importlib, jax\n"
        "jax.config.update('jax_enable_x64', True)\n"
        "import jaxrail.contact\n"
        "h = importlib.import_module('jaxrail.contact.hertz')\n"
        "from jax._src import xla_bridge\n"
        "assert h._table.cache_info().currsize == 0\n"
        "assert not xla_bridge._backends, xla_bridge._backends\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
