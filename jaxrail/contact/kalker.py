"""Kalker's creepage coefficients c11, c22, c23 of the linear theory of rolling contact.

Source: Kalker (1990), *Three-dimensional elastic bodies in rolling contact*, Table E.3,
as tabulated in CONTACT (`src/m_hertz.f90`, subroutine `linrol`) for Poisson's ratio
nu = 0, 0.25, 0.5 and 0.1 <= a/b <= 10 (``a`` the semi-axis along the rolling direction,
``b`` the lateral one). Linear theory, Kalker's sign convention (forces on the body,
opposing the creepage):

    Fx = -G a b c11 xi,        Fy = -G a b c22 eta - G (ab)^(3/2) c23 phi.

Smoothness (differs from CONTACT on purpose). CONTACT interpolates the table linearly
(C0) and switches to asymptotic formulas below g = min(a/b, b/a) = 0.101, where its
coefficients jump by up to 5 %. Here, for each coefficient and each tabulated nu:

- inside the table, ``log c`` is a cubic spline in ``x = log(a/b)`` through the 19 rows
  (C2, exact at the rows);
- outside, ``log c = log c_asym(x) + d0 exp(-p(u))``, ``u = |x - x0|`` (x0 the table
  end), ``p(u) = s u + (s u)^2 / 2 + (u / L)^3``: CONTACT's asymptote times a correction
  factor that decays monotonically to 1. d0 matches the value at the table end, s > 0
  the slope, and the spline's end condition ``S''(x0) = (log c_asym)''(x0)`` together
  with ``p'' = p'^2`` at u = 0 the curvature: C2 everywhere.

Between nu values CONTACT's rule is used: 1/c is quadratic in nu through nu = 0, 0.25,
0.5 (Lagrange). This reproduces the reference's nu = 0.28 and 0.30 columns at the rows.
Outside the table the result is blended (factor 1 - exp(-u^3), flat to second order at
the table end) into CONTACT's asymptote at the actual nu, which is not quadratic in 1/c.
Valid for 0 <= nu <= 0.5.

Table (the default, ``method="table"``). The function above costs ~75 logarithms and
exponentials per contact. Written as

    c = exp(beta(x) log(c_asym(x, nu) W(nu).Pa(x))) / (W(nu).P(x)),

with W the three Lagrange weights in nu, P = exp(-columns) and Pa = exp(-asymptote
columns) (9 functions of x each) and beta the blend factor, it needs only the nu-free
functions P, Pa, beta of x, which are tabulated as piecewise cubic Hermite interpolants
(values and exact derivatives at the nodes, built with NumPy at import) on a uniform
grid in x of step log(10)/230 with the table ends x = +-log 10 on nodes, for
|x| <= 6.01 (a/b in [2.5e-3, 400]); beyond, the blend and the end corrections are 1 and
0 to rounding and c = c_asym(x, nu) exactly. c_asym is algebraic in a/b, so what is
left is 1 logarithm of a/b, and beyond a/b of 0.1 to 10 (where beta > 0) 3 logarithms and
3 exponentials, computed only where some contact of a batch needs them
(:func:`jaxrail.compilation.seldom.seldom`). C1 in a/b (the Hermite
interpolant's second derivative jumps at the nodes, by ~1e-6 relative) and within
1e-6 relative of ``method="direct"`` (the evaluation above, the reference)
for all a/b > 0 and 0 <= nu <= 0.5 (tests/contact/test_kalker_table.py).
"""

import math

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..compilation.seldom import seldom

# Table E.3 of Kalker (1990) via CONTACT `linrol`. Rows: a/b = 0.1 ... 1.0, then
# b/a = 0.9 ... 0.1. Columns: c11 (nu = 0, .25, .5), c22 (same), c23 (same).
_TABLE = np.array(
    [
        [2.51, 3.31, 4.85, 2.51, 2.52, 2.53, 0.334, 0.473, 0.731],
        [2.59, 3.37, 4.81, 2.59, 2.63, 2.66, 0.483, 0.603, 0.809],
        [2.68, 3.44, 4.80, 2.68, 2.75, 2.81, 0.607, 0.715, 0.889],
        [2.78, 3.53, 4.82, 2.78, 2.88, 2.98, 0.720, 0.823, 0.977],
        [2.88, 3.62, 4.83, 2.88, 3.01, 3.14, 0.827, 0.929, 1.07],
        [2.98, 3.72, 4.91, 2.98, 3.14, 3.31, 0.930, 1.03, 1.18],
        [3.09, 3.81, 4.97, 3.09, 3.28, 3.48, 1.03, 1.14, 1.29],
        [3.19, 3.91, 5.05, 3.19, 3.41, 3.65, 1.13, 1.25, 1.40],
        [3.29, 4.01, 5.12, 3.29, 3.54, 3.82, 1.23, 1.36, 1.51],
        [3.40, 4.12, 5.20, 3.40, 3.67, 3.98, 1.33, 1.47, 1.63],
        [3.51, 4.22, 5.30, 3.51, 3.81, 4.16, 1.44, 1.59, 1.77],
        [3.65, 4.36, 5.42, 3.65, 3.99, 4.39, 1.58, 1.75, 1.94],
        [3.82, 4.54, 5.58, 3.82, 4.21, 4.67, 1.76, 1.95, 2.18],
        [4.06, 4.78, 5.80, 4.06, 4.50, 5.04, 2.01, 2.23, 2.50],
        [4.37, 5.10, 6.11, 4.37, 4.90, 5.56, 2.35, 2.62, 2.96],
        [4.84, 5.57, 6.57, 4.84, 5.48, 6.31, 2.88, 3.24, 3.70],
        [5.57, 6.34, 7.34, 5.57, 6.40, 7.51, 3.79, 4.32, 5.01],
        [6.96, 7.78, 8.82, 6.96, 8.14, 9.79, 5.72, 6.63, 7.89],
        [10.7, 11.7, 12.9, 10.7, 12.8, 16.0, 12.2, 14.6, 18.0],
    ]
)
TABLE_A_OVER_B = np.concatenate(
    [np.arange(1, 11) / 10.0, 1.0 / (np.arange(9, 0, -1) / 10.0)]
)
"""The 19 table rows, a/b = 0.1, 0.2, ..., 1.0, 1/0.9, 1/0.8, ..., 10 (NumPy, static)."""
TABLE_NU = np.array([0.0, 0.25, 0.5])
"""Poisson's ratios of the table columns (NumPy, static)."""
TABLE = _TABLE.reshape(19, 3, 3)
"""Table values, shape (19 rows, 3 coefficients c11/c22/c23, 3 nu) (NumPy, static)."""

_KAPPA = 3.0 - math.log(4.0)
_LN16 = math.log(16.0)
# Length [in log(a/b)] beyond which the cubic term of the correction's decay dominates.
_DECAY_LENGTH = 1.0
_X = np.log(TABLE_A_OVER_B)
_X_LO, _X_HI = float(_X[0]), float(_X[-1])


# --- asymptotes of CONTACT `linrol` in x = log(a/b) ----------------------------------------
# _asym_*: log c with its first two x-derivatives, NumPy, for the set-up of the joins.
# _log_asym_*: the same values only, jax.numpy, at run time.


def _asym_small(x, nu):
    """a << b (g = a/b = e^x): (log c11, log c22, log c23), each with d/dx, d2/dx2."""
    zero = 0.0 * x
    l11 = math.log(math.pi**2 / 4.0) - np.log(1.0 - nu) + zero
    l22 = math.log(math.pi**2 / 4.0) + zero + 0.0 * nu
    m = 1.0 + nu * (_LN16 - 5.0 - x)
    l23 = math.log(math.pi / 3.0) - np.log(1.0 - nu) + 0.5 * x + np.log(m)
    d23 = 0.5 - nu / m
    dd23 = -(nu**2) / m**2
    return (
        (l11, zero + 0.0 * nu, zero + 0.0 * nu),
        (l22, zero + 0.0 * nu, zero + 0.0 * nu),
        (l23, d23, dd23),
    )


def _asym_large(x, nu):
    """a >> b (g = b/a = e^-x, Lambda = ln16 + 2x): log c and derivatives, as above."""
    lam = _LN16 + 2.0 * x
    u = lam - 2.0 * nu  # c11 = 2 pi e^x (u + kappa) / u^2
    l11 = math.log(2.0 * math.pi) + x + np.log(u + _KAPPA) - 2.0 * np.log(u)
    d11 = 1.0 + 2.0 / (u + _KAPPA) - 4.0 / u
    dd11 = 8.0 / u**2 - 4.0 / (u + _KAPPA) ** 2
    w = (1.0 - nu) * lam + 2.0 * nu  # c22 = 2 pi e^x (w + (1-nu) kappa) / w^2
    wp = 2.0 * (1.0 - nu)
    wk = w + (1.0 - nu) * _KAPPA
    l22 = math.log(2.0 * math.pi) + x + np.log(wk) - 2.0 * np.log(w)
    d22 = 1.0 + wp / wk - 2.0 * wp / w
    dd22 = -(wp**2) / wk**2 + 2.0 * wp**2 / w**2
    z = (1.0 - nu) * lam - 2.0 + 4.0 * nu  # c23 = 2 pi e^(1.5 x) / (3 z)
    l23 = math.log(2.0 * math.pi / 3.0) + 1.5 * x - np.log(z)
    d23 = 1.5 - wp / z
    dd23 = wp**2 / z**2
    return ((l11, d11, dd11), (l22, d22, dd22), (l23, d23, dd23))


def _log_asym_small(x, nu):
    """log (c11, c22, c23) of the a << b asymptote, shape (3, *nu.shape); runtime."""
    ones = jnp.ones_like(nu)
    l11 = math.log(math.pi**2 / 4.0) - jnp.log(1.0 - nu)
    l22 = math.log(math.pi**2 / 4.0) * ones
    l23 = l11 - math.log(0.75 * math.pi) + 0.5 * x + jnp.log(1.0 + nu * (_LN16 - 5.0 - x))
    return jnp.stack([l11, l22, l23])


def _log_asym_large(x, nu):
    """log (c11, c22, c23) of the a >> b asymptote, shape (3, *nu.shape); runtime."""
    lam = _LN16 + 2.0 * x
    u = lam - 2.0 * nu
    w = (1.0 - nu) * lam + 2.0 * nu
    base = math.log(2.0 * math.pi) + x
    l11 = base + jnp.log(u + _KAPPA) - 2.0 * jnp.log(u)
    l22 = base + jnp.log(w + (1.0 - nu) * _KAPPA) - 2.0 * jnp.log(w)
    l23 = math.log(2.0 * math.pi / 3.0) + 1.5 * x - jnp.log(w - 2.0 * (1.0 - nu))
    return jnp.stack([l11, l22, l23])


def _cubic_spline(x, y, dd_first, dd_last):
    """Cubic spline through (x, y) with prescribed second derivatives at both ends.

    Returns coefficients (n-1, 4): on [x_i, x_i+1], S = c0 + c1 t + c2 t^2 + c3 t^3,
    t = x - x_i. Setup-time NumPy (the system is 19 x 19).
    """
    n = x.size
    h = np.diff(x)
    mat = np.zeros((n, n))
    rhs = np.zeros(n)
    mat[0, 0] = mat[-1, -1] = 1.0
    rhs[0], rhs[-1] = dd_first, dd_last
    for i in range(1, n - 1):
        mat[i, i - 1], mat[i, i], mat[i, i + 1] = h[i - 1], 2.0 * (h[i - 1] + h[i]), h[i]
        rhs[i] = 6.0 * ((y[i + 1] - y[i]) / h[i] - (y[i] - y[i - 1]) / h[i - 1])
    m = np.linalg.solve(mat, rhs)
    c1 = np.diff(y) / h - h * (2.0 * m[:-1] + m[1:]) / 6.0
    c3 = np.diff(m) / (6.0 * h)
    return np.stack([y[:-1], c1, m[:-1] / 2.0, c3], axis=1)


def _build():
    """Spline coefficients (9, 18, 4) and end-correction constants (9,) x 2 per side."""
    coefs, d0_lo, d1_lo, d0_hi, d1_hi = [], [], [], [], []
    for k in range(3):
        for j, nu in enumerate(TABLE_NU):
            y = np.log(TABLE[:, k, j])
            lo = _asym_small(_X_LO, nu)[k]
            hi = _asym_large(_X_HI, nu)[k]
            c = _cubic_spline(_X, y, float(lo[2]), float(hi[2]))
            h = _X[-1] - _X[-2]
            slope_hi = c[-1, 1] + 2.0 * c[-1, 2] * h + 3.0 * c[-1, 3] * h**2
            coefs.append(c)
            d0_lo.append(y[0] - lo[0])
            d1_lo.append(c[0, 1] - lo[1])
            d0_hi.append(y[-1] - hi[0])
            d1_hi.append(slope_hi - hi[1])
    d0_lo, d0_hi = np.array(d0_lo), np.array(d0_hi)
    # Decay rates in u = |x - x0| that match the slopes; all positive for this table,
    # which makes the correction monotone (no dip below or bump above the asymptote).
    s_lo = np.array(d1_lo) / d0_lo
    s_hi = -np.array(d1_hi) / d0_hi
    assert np.all(s_lo > 0.0) and np.all(s_hi > 0.0)
    return np.array(coefs), d0_lo, s_lo, d0_hi, s_hi


_COEFS, _D0_LO, _S_LO, _D0_HI, _S_HI = _build()


def _decay(u, s):
    """exp(-p(u)), p = s u + (s u)^2/2 + (u/L)^3: slope -s and zero curvature at u = 0."""
    su = s * u
    return jnp.exp(-(su + 0.5 * su * su + (u / _DECAY_LENGTH) ** 3))


def _nu_weights(nu):
    """Lagrange weights of 1/c at nu = 0, 0.25, 0.5 (CONTACT's interpolation)."""
    return jnp.stack(
        [8.0 * (nu - 0.25) * (nu - 0.5), -16.0 * (nu - 0.5) * nu, 8.0 * nu * (nu - 0.25)]
    )


def _log_nu_interp(log_cols, weights):
    """log c at nu from log c at nu = 0, .25, .5 (rows: c11, c22, c23), quadratic in 1/c."""
    return -jnp.log(jnp.exp(-log_cols).reshape(3, 3) @ weights)


@jnp.vectorize
def _log_kalker(a_over_b, nu):
    """(log c11, log c22, log c23) at one a/b > 0 and one nu."""
    f64 = jnp.float64
    x = jnp.log(a_over_b)
    nu3 = jnp.asarray(TABLE_NU, dtype=f64)

    # Each branch sees x clamped to its own range, so the unused branches stay finite
    # (and so do their gradients, which `where` multiplies by zero). Clamping by `where`,
    # not clip/min/max, which pass only half the gradient when x sits on the bound.
    below, above = x < _X_LO, x > _X_HI
    xs = jnp.where(below, _X_LO, jnp.where(above, _X_HI, x))
    x_lo = jnp.where(below, x, _X_LO)
    x_hi = jnp.where(above, x, _X_HI)

    # The 9 table columns (c11, c22, c23 at nu = 0, .25, .5): spline inside the table,
    # corrected asymptote outside. The asymptotes are evaluated at the table's nu and,
    # in the 4th column, at the actual nu.
    knots = jnp.asarray(_X[1:-1], dtype=f64)
    i = jnp.sum(xs >= knots)  # interval index, 0 ... 17 (no search loop to compile)
    t = xs - jnp.asarray(_X, dtype=f64)[i]
    c = jnp.asarray(_COEFS, dtype=f64)[:, i, :]
    spline = c[:, 0] + t * (c[:, 1] + t * (c[:, 2] + t * c[:, 3]))
    nu4 = jnp.concatenate([nu3, nu[None]])
    asym_lo = _log_asym_small(x_lo, nu4)  # (3, 4)
    asym_hi = _log_asym_large(x_hi, nu4)
    corr_lo = jnp.asarray(_D0_LO, dtype=f64) * _decay(_X_LO - x_lo, jnp.asarray(_S_LO, dtype=f64))
    corr_hi = jnp.asarray(_D0_HI, dtype=f64) * _decay(x_hi - _X_HI, jnp.asarray(_S_HI, dtype=f64))
    a_cols = jnp.where(below, asym_lo[:, :3], asym_hi[:, :3]).reshape(9)
    corr = jnp.where(below, corr_lo, corr_hi)
    columns = jnp.where(below | above, a_cols + corr, spline)

    weights = _nu_weights(nu)
    log_c = _log_nu_interp(columns, weights)

    # Outside the table, blend from the nu-interpolated columns to the asymptote at the
    # actual nu (the asymptotes are not quadratic in 1/c in nu: c23 would be 5 % off).
    # The blend factor 1 - exp(-u^3) is flat to second order at the table end (C2) and
    # leaves nu = 0, .25, .5 unchanged (there the two asymptote terms cancel).
    a_nu = jnp.where(below, asym_lo[:, 3], asym_hi[:, 3])
    u = (x_hi - _X_HI) + (_X_LO - x_lo)  # distance outside the table, 0 inside
    blend = 1.0 - jnp.exp(-(u**3))
    return log_c + blend * (a_nu - _log_nu_interp(a_cols, weights))


# --- the table (module docstring, "Table") ------------------------------------------------
_GRID_STEP = _X_HI / 230.0  # ~0.01; the table ends +-log 10 are nodes
_GRID_HALF = 600  # nodes on each side of x = 0: |x| <= 6.007
_GRID_END = _GRID_HALF * _GRID_STEP
METHODS = ("table", "direct")
"""Evaluation methods of :func:`kalker_coefficients`: ``"table"`` (default), ``"direct"``."""


def _columns_with_slopes(x):
    """The 9 columns log c (spline inside the table, corrected asymptote outside) and the
    9 asymptote columns (held constant inside the table), with x-derivatives. NumPy,
    x a 1-D grid; returns four (x.size, 9) arrays."""
    cols, dcols, acols, dacols = (np.zeros((x.size, 9)) for _ in range(4))
    below, above = x < _X_LO, x > _X_HI
    middle = ~(below | above)
    xs = np.clip(x, _X_LO, _X_HI)
    i = np.clip(np.searchsorted(_X, xs, side="right") - 1, 0, _X.size - 2)
    t = xs - _X[i]
    x_lo, x_hi = np.minimum(x, _X_LO), np.maximum(x, _X_HI)
    u_lo, u_hi = _X_LO - x_lo, x_hi - _X_HI
    for k in range(3):
        for j, nu in enumerate(TABLE_NU):
            col = 3 * k + j
            c = _COEFS[col][i]
            spline = c[:, 0] + t * (c[:, 1] + t * (c[:, 2] + t * c[:, 3]))
            dspline = c[:, 1] + t * (2.0 * c[:, 2] + 3.0 * t * c[:, 3])
            lo, hi = _asym_small(x_lo, nu)[k], _asym_large(x_hi, nu)[k]
            decay = []
            for u, s, d0 in ((u_lo, _S_LO[col], _D0_LO[col]), (u_hi, _S_HI[col], _D0_HI[col])):
                e = d0 * np.exp(-(s * u + 0.5 * (s * u) ** 2 + (u / _DECAY_LENGTH) ** 3))
                de_du = -(s + s * s * u + 3.0 * u * u / _DECAY_LENGTH**3) * e
                decay.append((e, de_du))
            (e_lo, de_lo), (e_hi, de_hi) = decay
            cols[:, col] = np.where(below, lo[0] + e_lo, np.where(above, hi[0] + e_hi, spline))
            dcols[:, col] = np.where(below, lo[1] - de_lo, np.where(above, hi[1] + de_hi, dspline))
            # Inside the table the blend factor is 0 and the asymptote columns only have
            # to be finite: the value at the nearer table end, slope 0.
            acols[:, col] = np.where(x < 0.0, lo[0], hi[0])
            dacols[:, col] = np.where(middle, 0.0, np.where(below, lo[1], hi[1]))
    return cols, dcols, acols, dacols


def _build_table():
    """(nodes, 38) NumPy: P (9), Pa (9), beta at the grid nodes, then their slopes."""
    x = np.arange(-_GRID_HALF, _GRID_HALF + 1) * _GRID_STEP
    cols, dcols, acols, dacols = _columns_with_slopes(x)
    p, pa = np.exp(-cols), np.exp(-acols)
    u = np.maximum(x - _X_HI, 0.0) + np.maximum(_X_LO - x, 0.0)
    beta = 1.0 - np.exp(-(u**3))
    dbeta = 3.0 * u * u * np.exp(-(u**3)) * np.sign(x)
    table = np.concatenate(
        [p, pa, beta[:, None], -dcols * p, -dacols * pa, dbeta[:, None]], axis=1
    )
    table.setflags(write=False)
    return table


_TABLE_NODES = _build_table()


def _asymptote(ratio, x, nu):
    """CONTACT's asymptotic (c11, c22, c23) at the actual nu (stacked, axis 0): the
    a << b form for x < 0, the a >> b form for x > 0, each at x clamped outside the
    table (algebraic in a/b: no exponential)."""
    small, large = x < _X_LO, x > _X_HI
    g_lo = jnp.where(small, ratio, 0.1)
    x_lo = jnp.where(small, x, _X_LO)
    g_hi = jnp.where(large, ratio, 10.0)
    x_hi = jnp.where(large, x, _X_HI)
    one_minus = 1.0 - nu
    c11_lo = (math.pi**2 / 4.0) / one_minus
    c22_lo = (math.pi**2 / 4.0) * jnp.ones_like(x)
    c23_lo = math.pi / (3.0 * one_minus) * jnp.sqrt(g_lo) * (1.0 + nu * (_LN16 - 5.0 - x_lo))
    lam = _LN16 + 2.0 * x_hi
    u = lam - 2.0 * nu
    w = one_minus * lam + 2.0 * nu
    two_pi_g = 2.0 * math.pi * g_hi
    c11_hi = two_pi_g * (u + _KAPPA) / (u * u)
    c22_hi = two_pi_g * (w + one_minus * _KAPPA) / (w * w)
    c23_hi = two_pi_g * jnp.sqrt(g_hi) / (3.0 * (w - 2.0 * one_minus))
    left = x < 0.0
    return jnp.stack(
        [jnp.where(left, c11_lo, c11_hi), jnp.where(left, c22_lo, c22_hi),
         jnp.where(left, c23_lo, c23_hi)]
    )


def _kalker_table(a_over_b, nu):
    """(c11, c22, c23) stacked on axis 0, from the table (module docstring)."""
    x = jnp.log(a_over_b)
    inside = jnp.abs(x) <= _GRID_END
    grid = (jnp.where(inside, x, 0.0) + _GRID_END) / _GRID_STEP
    i = jnp.clip(jnp.floor(grid), 0, 2 * _GRID_HALF - 1).astype(jnp.int32)
    s = (grid - i)[..., None]
    ends = jnp.asarray(_TABLE_NODES)[jnp.stack([i, i + 1], axis=-1)]  # (..., 2, 38)
    f0, d0 = ends[..., 0, :19], ends[..., 0, 19:] * _GRID_STEP
    f1, d1 = ends[..., 1, :19], ends[..., 1, 19:] * _GRID_STEP
    r = 1.0 - s
    f = r * r * ((1.0 + 2.0 * s) * f0 + s * d0) + s * s * ((3.0 - 2.0 * s) * f1 - r * d1)
    weights = _nu_weights(nu)  # (3, ...)
    p = jnp.moveaxis(f[..., :9].reshape(f.shape[:-1] + (3, 3)), -2, 0)  # (3 coeffs, ..., 3 nu)
    pa = jnp.moveaxis(f[..., 9:18].reshape(f.shape[:-1] + (3, 3)), -2, 0)
    beta = f[..., 18]
    w_last = jnp.moveaxis(weights, 0, -1)  # (..., 3)
    inv_c = jnp.sum(p * w_last, axis=-1)
    # Within a/b of 0.1 to 10 the blend factor beta is 0 (at the nodes and so between
    # them): c = 1 / inv_c. Beyond, the blend toward the asymptote, computed only where
    # some contact of the batch needs it.
    outer = jnp.abs(x) > _X_HI
    pa_sum = jnp.moveaxis(jnp.sum(pa * w_last, axis=-1), 0, -1)  # (..., 3)
    blend, asym = seldom(_outer_terms, outer, a_over_b, x, nu, beta, pa_sum)
    blend, asym = jnp.moveaxis(blend, -1, 0), jnp.moveaxis(asym, -1, 0)
    blended = jnp.where(outer, blend, 1.0) / inv_c
    return jnp.where(inside, blended, asym)


def _outer_terms(ratio, x, nu, beta, pa_sum):
    """(blend factors (3,), asymptote (3,)) at one a/b beyond 0.1 to 10 (``pa_sum``
    (3,): the Pa columns weighted in nu)."""
    asym = _asymptote(ratio, x, nu)
    return jnp.exp(beta * jnp.log(asym * pa_sum)), asym


def kalker_coefficients(
    a_over_b: Float[ArrayLike, "*batch"],
    nu: Float[ArrayLike, "*batch"],
    method: str = "table",
) -> tuple[Float[Array, "*batch"], Float[Array, "*batch"], Float[Array, "*batch"]]:
    """Kalker's linear creepage coefficients ``(c11, c22, c23)`` [-].

    **Arguments:**

    - `a_over_b`: ratio of the contact-ellipse semi-axes, ``a`` along the rolling
      direction over ``b`` lateral [-], > 0. Any positive value: the table covers
      0.1 ... 10, beyond it the coefficients join CONTACT's asymptotes smoothly.
    - `nu`: Poisson's ratio [-], 0 <= nu <= 0.5 (combined value of the two bodies).

    - `method`: ``"table"`` (default: tabulated, C1, within 1e-6 relative of
      ``"direct"``) or ``"direct"`` (the defining evaluation: C2, reproduces the table
      rows exactly). See the module docstring.

    Arguments broadcast against each other; results have the broadcast shape.
    Smooth in ``a/b`` and polynomial in ``nu`` (see the module docstring), so
    jit/vmap/grad-safe.
    """
    a_over_b = jnp.asarray(a_over_b, dtype=jnp.float64)
    nu = jnp.asarray(nu, dtype=jnp.float64)
    if method == "table":
        a_over_b, nu = jnp.broadcast_arrays(a_over_b, nu)
        out = _kalker_table(a_over_b, nu)
        return out[0], out[1], out[2]
    if method != "direct":
        raise ValueError(f"kalker_coefficients: method must be one of {METHODS}, got {method!r}")
    out = jnp.exp(_log_kalker(a_over_b, nu))
    return out[..., 0], out[..., 1], out[..., 2]


def kalker_asymptotes(
    a_over_b: Float[ArrayLike, ""], nu: Float[ArrayLike, ""]
) -> tuple[Float[Array, ""], Float[Array, ""], Float[Array, ""]]:
    """CONTACT's asymptotic ``(c11, c22, c23)`` for ``a/b -> 0`` (if a/b < 1) or
    ``a/b -> infinity`` (if a/b >= 1). For comparison and plots; scalar arguments."""
    x = jnp.log(jnp.asarray(a_over_b, dtype=jnp.float64))
    nu = jnp.asarray(nu, dtype=jnp.float64)
    lo = _log_asym_small(jnp.where(x < 0.0, x, 0.0), nu)
    hi = _log_asym_large(jnp.where(x < 0.0, 0.0, x), nu)
    c = jnp.exp(jnp.where(x < 0.0, lo, hi))
    return c[0], c[1], c[2]
