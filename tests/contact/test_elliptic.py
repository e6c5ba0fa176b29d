"""Complete elliptic integrals: values vs scipy/mpmath, derivatives vs formulas and FD."""

import jax
import mpmath
import numpy as np
import pytest
from scipy import special

from jaxrail.contact.elliptic import agm_kq, ellipe, ellipk, ellipke, ellipke_complementary

VALUE_RTOL = 1e-14

# Dense interior grid, the ends near m = 0 and a log-spaced approach to m = 1.
M_GRID = np.concatenate(
    [[0.0, 1e-300, 1e-16, 1e-8], np.linspace(0.0, 1.0, 401)[:-1], 1.0 - np.logspace(-12, -1, 60)]
)

_PAD = 512


def _padded(kernel):
    """jit(vmap(kernel)) on inputs padded to _PAD values (pad value 0.5), so that each
    kernel compiles once for the whole module."""
    compiled = jax.jit(jax.vmap(kernel))

    def call(*args):
        args = [np.asarray(x, dtype=np.float64) for x in args]
        size = args[0].size
        full = [np.concatenate([x.ravel(), np.full(_PAD - size, 0.5)]) for x in args]
        return jax.tree_util.tree_map(lambda y: np.asarray(y)[:size], compiled(*full))

    return call


_ke = _padded(ellipke)
_ke_c = _padded(ellipke_complementary)
_dke = _padded(jax.jacfwd(ellipke))
_dke_c = _padded(jax.jacfwd(ellipke_complementary))
_d2k = _padded(jax.grad(jax.grad(ellipk)))
_kq = _padded(agm_kq)


def test_values_match_scipy():
    k, e = _ke(M_GRID)
    np.testing.assert_allclose(k, special.ellipk(M_GRID), rtol=VALUE_RTOL, atol=0)
    np.testing.assert_allclose(e, special.ellipe(M_GRID), rtol=VALUE_RTOL, atol=0)


def test_special_values_and_legendre_relation():
    k, e = _ke(np.array([0.0, 1.0, 0.3, 0.7]))
    assert float(k[0]) == pytest.approx(np.pi / 2, rel=1e-16)
    assert float(e[0]) == pytest.approx(np.pi / 2, rel=1e-16)
    assert float(k[1]) == np.inf
    assert float(e[1]) == 1.0
    # Legendre's relation E K' + E' K - K K' = pi/2 (m = 0.3, m' = 0.7).
    assert float(e[2] * k[3] + e[3] * k[2] - k[2] * k[3]) == pytest.approx(np.pi / 2, rel=1e-14)


def test_near_one_against_mpmath_and_ellipkm1():
    mpmath.mp.dps = 40
    m1 = np.array([1e-12, 1e-9, 1e-6, 1e-3])
    k, e = _ke_c(m1)
    for i, x in enumerate(m1):
        assert float(k[i]) == pytest.approx(float(mpmath.ellipk(1 - mpmath.mpf(x))), rel=VALUE_RTOL)
        assert float(e[i]) == pytest.approx(float(mpmath.ellipe(1 - mpmath.mpf(x))), rel=VALUE_RTOL)
    m1 = np.logspace(-14, 0, 50)
    np.testing.assert_allclose(_ke_c(m1)[0], special.ellipkm1(m1), rtol=VALUE_RTOL)


def test_derivatives_match_formulas():
    # The textbook formulas, evaluated with scipy values where they are well conditioned.
    m = np.concatenate([np.linspace(1e-2, 0.99, 50), 1.0 - np.logspace(-9, -3, 10)])
    k, e = special.ellipk(m), special.ellipe(m)
    dk, de = _dke(m)
    np.testing.assert_allclose(dk, (e - (1 - m) * k) / (2 * m * (1 - m)), rtol=1e-11)
    np.testing.assert_allclose(de, (e - k) / (2 * m), rtol=1e-11)


def test_derivatives_at_and_near_zero():
    # K = pi/2 (1 + m/4 + 9 m^2/64 + ...), E = pi/2 (1 - m/4 - 3 m^2/64 - ...).
    m = np.array([0.0, 1e-6])
    dk, de = _dke(m)
    assert float(dk[0]) == pytest.approx(np.pi / 8, rel=1e-15)
    assert float(de[0]) == pytest.approx(-np.pi / 8, rel=1e-15)
    assert float(dk[1]) == pytest.approx(np.pi / 2 * (0.25 + 9 * m[1] / 32), rel=1e-11)
    assert float(de[1]) == pytest.approx(np.pi / 2 * (-0.25 - 3 * m[1] / 32), rel=1e-11)


def test_derivatives_vs_central_differences_of_scipy():
    m = np.array([0.05, 0.3, 0.7, 0.95, 0.9999])
    h = 1e-6 * np.minimum(m, 1 - m)
    dk, de = _dke(m)
    fd_k = (special.ellipk(m + h) - special.ellipk(m - h)) / (2 * h)
    fd_e = (special.ellipe(m + h) - special.ellipe(m - h)) / (2 * h)
    np.testing.assert_allclose(dk, fd_k, rtol=1e-7)
    np.testing.assert_allclose(de, fd_e, rtol=1e-7)


def test_complementary_derivative_and_second_derivative():
    m1 = np.array([1e-4, 0.5])
    h = 1e-6 * m1
    dk, de = _dke_c(m1)
    fd_k = (special.ellipkm1(m1 + h) - special.ellipkm1(m1 - h)) / (2 * h)
    fd_e = (special.ellipe(1 - m1 - h) - special.ellipe(1 - m1 + h)) / (2 * h)
    np.testing.assert_allclose(dk, fd_k, rtol=1e-7)
    np.testing.assert_allclose(de, fd_e, rtol=1e-7)

    # Second derivative: central difference of the (scipy-evaluated) derivative formula.
    def dk_formula(x):
        k, e = special.ellipk(x), special.ellipe(x)
        return (e - (1 - x) * k) / (2 * x * (1 - x))

    m, h = np.array([0.4, 0.9]), 1e-5
    np.testing.assert_allclose(
        _d2k(m), (dk_formula(m + h) - dk_formula(m - h)) / (2 * h), rtol=1e-7
    )


def test_agm_tail_is_cancellation_free_near_zero():
    # K - E = m K (1/2 + Q) and E - (1-m) K = m K (1/2 - Q) must keep full relative
    # accuracy for tiny m, where K and E agree to many digits. Reference: mpmath.
    mpmath.mp.dps = 50
    m = np.array([1e-12, 1e-8, 1e-5, 1e-2])
    k, q = _kq(m, 1.0 - m)
    for i, x in enumerate(m):
        xm = mpmath.mpf(x)
        km, em = mpmath.ellipk(xm), mpmath.ellipe(xm)
        assert float(k[i] * (0.5 + q[i])) == pytest.approx(float((km - em) / xm), rel=1e-14)
        assert float(k[i] * (0.5 - q[i])) == pytest.approx(
            float((em - (1 - xm) * km) / xm), rel=1e-14
        )


def test_jit_vmap_grad_shapes_and_finiteness():
    m = np.linspace(0.0, 1.0 - 1e-12, 7)
    k, e = _ke(m)
    assert k.shape == e.shape == (7,)
    assert k.dtype == np.float64
    dk, de = _dke(m)
    assert np.all(np.isfinite(dk)) and np.all(np.isfinite(de))
    # The scalar (unbatched, eager) entry points agree with the batched kernels.
    assert float(ellipk(m[3])) == pytest.approx(float(k[3]), rel=1e-15)
    assert float(ellipe(m[3])) == pytest.approx(float(e[3]), rel=1e-15)
    assert float(jax.grad(ellipk)(m[3])) == pytest.approx(float(dk[3]), rel=1e-15)
