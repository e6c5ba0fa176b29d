"""Kalker coefficients: table, nu interpolation, smoothness, asymptotes, AD.

These test the defining evaluation (``method="direct"``: spline and asymptotes), the
reference; the default tabulated path is tested against it in test_kalker_table.py."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from jaxrail.contact import kalker
from jaxrail.contact.kalker import kalker_asymptotes
from jaxrail.contact.kalker import kalker_coefficients as _kalker_coefficients


def kalker_coefficients(a_over_b, nu):
    return _kalker_coefficients(a_over_b, nu, method="direct")

# Printed table of reference/contact-mechanics.md 4.1 (independent copy): a/b, then
# c11, c22, c23 at nu = 0, .25, .5, then the nu = 0.28 and 0.30 columns (CONTACT's rule).
PRINTED = """
0.1 | 2.51 | 3.31 | 4.85 | 2.51 | 2.52 | 2.53 | 0.334 | 0.473 | 0.731 | 3.441 | 2.521 | 0.496 | 3.535 | 2.522 | 0.512
0.2 | 2.59 | 3.37 | 4.81 | 2.59 | 2.63 | 2.66 | 0.483 | 0.603 | 0.809 | 3.496 | 2.634 | 0.622 | 3.585 | 2.637 | 0.635
0.3 | 2.68 | 3.44 | 4.80 | 2.68 | 2.75 | 2.81 | 0.607 | 0.715 | 0.889 | 3.561 | 2.758 | 0.731 | 3.647 | 2.763 | 0.743
0.4 | 2.78 | 3.53 | 4.82 | 2.78 | 2.88 | 2.98 | 0.720 | 0.823 | 0.977 | 3.648 | 2.892 | 0.838 | 3.730 | 2.900 | 0.849
0.5 | 2.88 | 3.62 | 4.83 | 2.88 | 3.01 | 3.14 | 0.827 | 0.929 | 1.07 | 3.734 | 3.026 | 0.943 | 3.813 | 3.036 | 0.953
0.6 | 2.98 | 3.72 | 4.91 | 2.98 | 3.14 | 3.31 | 0.930 | 1.03 | 1.18 | 3.833 | 3.160 | 1.045 | 3.911 | 3.173 | 1.055
0.7 | 3.09 | 3.81 | 4.97 | 3.09 | 3.28 | 3.48 | 1.03 | 1.14 | 1.29 | 3.920 | 3.303 | 1.156 | 3.996 | 3.319 | 1.166
0.8 | 3.19 | 3.91 | 5.05 | 3.19 | 3.41 | 3.65 | 1.13 | 1.25 | 1.40 | 4.019 | 3.438 | 1.266 | 4.095 | 3.456 | 1.277
0.9 | 3.29 | 4.01 | 5.12 | 3.29 | 3.54 | 3.82 | 1.23 | 1.36 | 1.51 | 4.118 | 3.572 | 1.377 | 4.192 | 3.593 | 1.388
1.0 | 3.40 | 4.12 | 5.20 | 3.40 | 3.67 | 3.98 | 1.33 | 1.47 | 1.63 | 4.226 | 3.705 | 1.488 | 4.300 | 3.729 | 1.500
1.111 | 3.51 | 4.22 | 5.30 | 3.51 | 3.81 | 4.16 | 1.44 | 1.59 | 1.77 | 4.325 | 3.849 | 1.610 | 4.399 | 3.876 | 1.623
1.25 | 3.65 | 4.36 | 5.42 | 3.65 | 3.99 | 4.39 | 1.58 | 1.75 | 1.94 | 4.465 | 4.035 | 1.772 | 4.537 | 4.065 | 1.786
1.429 | 3.82 | 4.54 | 5.58 | 3.82 | 4.21 | 4.67 | 1.76 | 1.95 | 2.18 | 4.644 | 4.261 | 1.975 | 4.717 | 4.296 | 1.992
1.667 | 4.06 | 4.78 | 5.80 | 4.06 | 4.50 | 5.04 | 2.01 | 2.23 | 2.50 | 4.883 | 4.559 | 2.259 | 4.955 | 4.599 | 2.280
2.0 | 4.37 | 5.10 | 6.11 | 4.37 | 4.90 | 5.56 | 2.35 | 2.62 | 2.96 | 5.204 | 4.971 | 2.657 | 5.275 | 5.020 | 2.682
2.5 | 4.84 | 5.57 | 6.57 | 4.84 | 5.48 | 6.31 | 2.88 | 3.24 | 3.70 | 5.673 | 5.568 | 3.289 | 5.744 | 5.628 | 3.323
3.333 | 5.57 | 6.34 | 7.34 | 5.57 | 6.40 | 7.51 | 3.79 | 4.32 | 5.01 | 6.446 | 6.516 | 4.393 | 6.519 | 6.596 | 4.443
5.0 | 6.96 | 7.78 | 8.82 | 6.96 | 8.14 | 9.79 | 5.72 | 6.63 | 7.89 | 7.892 | 8.308 | 6.759 | 7.968 | 8.425 | 6.848
10 | 10.7 | 11.7 | 12.9 | 10.7 | 12.8 | 16.0 | 12.2 | 14.6 | 18.0 | 11.832 | 13.112 | 14.945 | 11.922 | 13.329 | 15.183
"""
ROWS = np.array([[float(v) for v in line.split("|")] for line in PRINTED.strip().splitlines()])
# The printed a/b of the b/a rows is rounded (1.111 for 1/0.9); use the exact ratios.
A_OVER_B = np.concatenate([np.arange(1, 11) / 10.0, 1.0 / (np.arange(9, 0, -1) / 10.0)])
PRINTED_TOL = 0.5e-3 + 1e-12  # half a unit of the last printed digit (3 decimals)

N_PAD = 64  # every batched call is padded to this length: one compilation per helper


@jax.jit
def _batch(r, nu):
    return jnp.stack(jax.vmap(kalker_coefficients)(r, nu))


def kalker_batch(r, nu):
    """(3, len(r)) coefficients at a/b = r (<= N_PAD values), one jitted shape."""
    r = np.atleast_1d(np.asarray(r, dtype=float))
    nu = np.broadcast_to(np.asarray(nu, dtype=float), r.shape)
    n = r.size
    rp = np.concatenate([r, np.ones(N_PAD - n)])
    nup = np.concatenate([nu, np.full(N_PAD - n, 0.25)])
    return np.array(_batch(rp, nup))[:, :n]


def _log_c(x, nu):
    return jnp.log(jnp.stack(kalker_coefficients(jnp.exp(x), nu)))


@jax.jit
def _derivatives(x, nu):
    """log c_k and its first two derivatives in x = log(a/b): three (N_PAD, 3) arrays."""
    d1 = jax.jacfwd(_log_c)
    d2 = jax.jacfwd(d1)
    return jax.vmap(_log_c, (0, None))(x, nu), jax.vmap(d1, (0, None))(x, nu), jax.vmap(d2, (0, None))(x, nu)


def derivatives(x, nu):
    x = np.asarray(x, dtype=float)
    n = x.size
    out = _derivatives(np.concatenate([x, np.zeros(N_PAD - n)]), nu)
    return tuple(np.array(o)[:n] for o in out)


def printed_decimals(v):
    return 3 if v < 1.0 else 2 if v < 10 else 1


@pytest.mark.parametrize("j, nu", [(0, 0.0), (1, 0.25), (2, 0.5)])
def test_table_rows_reproduced(j, nu):
    c = kalker_batch(A_OVER_B, nu).T  # (19, 3)
    for k in range(3):
        printed = ROWS[:, 1 + 3 * k + j]
        # exact at the rows, so the printed digits come back
        np.testing.assert_allclose(c[:, k], printed, rtol=1e-13)
        for value, p in zip(c[:, k], printed):
            assert round(float(value), printed_decimals(p)) == pytest.approx(p, abs=1e-12)


@pytest.mark.parametrize("col, nu", [(10, 0.28), (13, 0.30)])
def test_nu_columns_of_contact_interpolation(col, nu):
    c = kalker_batch(A_OVER_B, nu).T
    for k in range(3):
        np.testing.assert_array_less(np.abs(c[:, k] - ROWS[:, col + k]), PRINTED_TOL)


def test_nu_interpolation_between_rows_is_quadratic_in_inverse():
    # Away from the rows: 1/c(nu) must be the Lagrange quadratic of 1/c(0, .25, .5).
    r = np.array([0.137, 0.55, 1.9, 7.3])
    base = [kalker_batch(r, nu) for nu in (0.0, 0.25, 0.5)]
    nu = 0.28
    w = [8 * (nu - 0.25) * (nu - 0.5), -16 * (nu - 0.5) * nu, 8 * nu * (nu - 0.25)]
    expected = 1.0 / sum(wi / bi for wi, bi in zip(w, base))
    np.testing.assert_allclose(kalker_batch(r, nu), expected, rtol=1e-12)


_asymptotes_batch = jax.jit(jax.vmap(kalker_asymptotes, (0, None)))


def log_asymptote_second_derivative(x, nu, h=1e-4):
    """d2/dx2 of log c_asym at x = log(a/b), by central differences (3 values)."""
    r = np.exp(np.array([x - h, x, x + h]))
    la = np.log(np.array(_asymptotes_batch(r, nu)))  # (3 coefficients, 3 points)
    return (la[:, 2] - 2 * la[:, 1] + la[:, 0]) / h**2


@pytest.mark.parametrize("nu", [0.0, 0.25, 0.5])
def test_spline_matches_scipy_with_same_end_conditions(nu):
    # Independent spline construction: scipy CubicSpline through the table with the
    # second derivatives of the log-asymptotes as end conditions.
    j = [0.0, 0.25, 0.5].index(nu)
    x = np.log(A_OVER_B)
    xm = 0.5 * (x[1:] + x[:-1])
    dd_lo = log_asymptote_second_derivative(x[0], nu)
    dd_hi = log_asymptote_second_derivative(x[-1], nu)
    ours = np.log(kalker_batch(np.exp(xm), nu))
    for k in range(3):
        y = np.log(kalker.TABLE[:, k, j])
        spline = CubicSpline(x, y, bc_type=((2, dd_lo[k]), (2, dd_hi[k])))
        # the end conditions are known to ~1e-7 (finite differences); their effect on
        # the spline is ~1e-9 next to the ends
        np.testing.assert_allclose(ours[k], spline(xm), rtol=0, atol=1e-8)


@pytest.mark.parametrize("nu", [0.0, 0.25, 0.28, 0.5])
def test_c2_across_table_rows_and_ends(nu):
    x = np.log(A_OVER_B)
    h = 1e-7
    _, left1, left2 = derivatives(x - h, nu)
    _, right1, right2 = derivatives(x + h, nu)
    # no jumps in first and second derivative (changes over 2h are O(h))
    np.testing.assert_allclose(left1, right1, rtol=0, atol=1e-5)
    np.testing.assert_allclose(left2, right2, rtol=0, atol=1e-5)
    # and the derivatives are the true ones: central differences of value and slope
    # (the third derivative jumps at the rows, so the d2 check is good to O(h))
    hf = 1e-6
    v_p, d1_p, _ = derivatives(x + hf, nu)
    v_m, d1_m, _ = derivatives(x - hf, nu)
    _, d1, d2 = derivatives(x, nu)
    np.testing.assert_allclose(d1, (v_p - v_m) / (2 * hf), rtol=0, atol=1e-8)
    np.testing.assert_allclose(d2, (d1_p - d1_m) / (2 * hf), rtol=0, atol=1e-4)


def test_linear_interpolation_would_have_kinks():
    # Sanity of the smoothness test: the slope of the table's piecewise-linear
    # interpolation jumps at the rows by far more than the tolerance used above.
    x = np.log(A_OVER_B)
    slopes = np.diff(np.log(kalker.TABLE[:, 2, 1])) / np.diff(x)
    assert np.max(np.abs(np.diff(slopes))) > 1e-2


@pytest.mark.parametrize("nu", [0.0, 0.25, 0.5])
def test_asymptotes_approached(nu):
    for r in (1e-3, 1e-4, 1e3, 1e4):
        ours = kalker_batch(r, nu)[:, 0]
        asym = np.array(kalker_asymptotes(r, nu))
        np.testing.assert_allclose(ours, asym, rtol=1e-6)
    # closed forms of the a << b asymptotes (reference 4.1)
    g = 1e-4
    c11, c22, c23 = kalker_batch(g, nu)[:, 0]
    assert c11 == pytest.approx(math.pi**2 / (4 * (1 - nu)), rel=1e-6)
    assert c22 == pytest.approx(math.pi**2 / 4, rel=1e-6)
    c23_asym = math.pi * math.sqrt(g) / (3 * (1 - nu)) * (1 + nu * (math.log(16 / g) - 5))
    assert c23 == pytest.approx(c23_asym, rel=1e-6)
    # a >> b
    g = 1e-4
    lam = math.log(16 / g**2)
    c11, c22, c23 = kalker_batch(1 / g, nu)[:, 0]
    kap = 3 - math.log(4)
    assert c11 == pytest.approx(2 * math.pi / ((lam - 2 * nu) * g) * (1 + kap / (lam - 2 * nu)), rel=1e-6)
    w = (1 - nu) * lam + 2 * nu
    assert c22 == pytest.approx(2 * math.pi / g * (1 + (1 - nu) * kap / w) / w, rel=1e-6)
    assert c23 == pytest.approx(2 * math.pi / (3 * g**1.5 * ((1 - nu) * lam - 2 + 4 * nu)), rel=1e-6)


@pytest.mark.parametrize("nu", [0.0, 0.25, 0.5])
def test_join_to_asymptote_is_monotone(nu):
    # The correction factor c / c_asym moves monotonically from its table-end value to 1.
    for rs in (np.geomspace(0.1, 1e-4, 60), np.geomspace(10, 1e4, 60)):
        asym = np.array(_asymptotes_batch(rs, nu))
        ratio = kalker_batch(rs, nu) / asym
        dev = np.abs(np.log(ratio))
        assert np.all(np.diff(dev, axis=1) <= 1e-15)


def test_asymptotic_region_at_intermediate_nu():
    # Far outside the table the coefficients are CONTACT's asymptotes at the actual nu
    # (not the nu-quadratic of the three tabulated asymptotes, 5 % off for c23).
    for r in (1e-3, 1e3):
        ours = kalker_batch(r, 0.28)[:, 0]
        asym = np.array(kalker_asymptotes(r, 0.28))
        np.testing.assert_allclose(ours, asym, rtol=1e-6)
    ours = kalker_batch(1e-4, 0.28)[:, 0]
    np.testing.assert_allclose(ours[:2], [math.pi**2 / (4 * 0.72), math.pi**2 / 4], rtol=1e-6)


def test_vmap_and_broadcast_match_scalar_calls():
    r = np.array([0.05, 0.3, 1.0, 2.2, 15.0])
    nu = np.array([0.0, 0.1, 0.28, 0.3, 0.5])
    batched = kalker_batch(r, nu)  # jit(vmap)
    broadcast = np.array(jax.jit(_stacked)((r, nu)))  # array arguments broadcast
    for i in range(r.size):
        single = np.array(_value(np.array([r[i], nu[i]])))  # jit, scalar arguments
        np.testing.assert_allclose(batched[:, i], single, rtol=1e-14)
        np.testing.assert_allclose(broadcast[:, i], single, rtol=1e-14)


def _stacked(v):
    return jnp.stack(kalker_coefficients(v[0], v[1]))


_jac_rev = jax.jit(jax.jacrev(_stacked))
_jac_fwd = jax.jit(jax.jacfwd(_stacked))
_value = jax.jit(_stacked)


@pytest.mark.parametrize("r", [0.003, 0.07, 0.1, 0.45, 1.0, 3.7, 10.0, 40.0])
def test_grad_matches_central_differences(r, central_jacobian):
    v = np.array([r, 0.28])
    jac = np.array(_jac_rev(v))
    fd = central_jacobian(_value, v, (1e-6 * r, 1e-6))
    np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(np.array(_jac_fwd(v)), jac, rtol=1e-12, atol=1e-20)
