"""Monotone cubic Hermite tables: values and exact integrals, C1, exact at the points.

A table (x_k, y_k), x strictly increasing, is interpolated by the cubic Hermite
polynomial of each interval with the slopes d_k of Fritsch and Carlson (SIAM J. Numer.
Anal. 17 (1980) 238-246), as scipy's ``PchipInterpolator`` makes them: the weighted
harmonic mean of the neighbouring secants where they have the same sign, 0 where they
do not, and the shape-preserving three-point formula at the ends. The interpolant

* passes through every point (the Hermite basis is 1 and 0 at the interval's ends),
* is continuously differentiable (neighbouring intervals share d_k at x_k),
* is monotone wherever the table is (a non-decreasing table gives a non-decreasing
  curve: the slopes stay inside the Fritsch-Carlson region),
* continues beyond the ends along the end slopes' lines, so it stays C1 there too.

Its integral from x_0 is exact: on [x_k, x_k+1] with h = x_k+1 - x_k and
t = (x - x_k) / h, the Hermite cubic is y_k h00 + h d_k h10 + y_k+1 h01 + h d_k+1 h11
and its integral h (y_k H00 + h d_k H10 + y_k+1 H01 + h d_k+1 H11) with

    H00 = t^4/2 - t^3 + t,   H10 = t^4/4 - 2 t^3/3 + t^2/2,
    H01 = -t^4/2 + t^3,      H11 = t^4/4 - t^3/3,

a whole interval giving h (y_k + y_k+1) / 2 + h^2 (d_k - d_k+1) / 12; beyond the ends
the lines integrate to y_end e + d_end e^2 / 2, e the distance past the end. A force
made from such a table and an energy made from its integral are therefore consistent to
rounding (the energy of a conservative system is kept).

The slopes are made in numpy when an element is built and travel as traced arrays
beside the points and values: evaluating is a handful of traced operations,
differentiable in the argument and in x, y and d (a gradient in y holds d fixed).
Intervals are selected by one-hot products, not gathers (cheaper to compile on CPU).
"""

import jax.numpy as jnp
import numpy as np


def check_table(x, y, what: str, names=("displacements", "forces")) -> tuple[np.ndarray,
                                                                           np.ndarray]:
    """(x, y) as float arrays, or a ValueError naming ``what`` and the columns'
    ``names``: two columns of equal length >= 2, finite, x strictly increasing and y
    non-decreasing (monotone)."""
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    if x.ndim != 1 or x.shape != y.shape or x.size < 2:
        raise ValueError(f"{what}: a table needs two columns of equal length >= 2, got "
                         f"shapes {x.shape} and {y.shape}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError(f"{what}: the table's values must be finite, got {x.tolist()} "
                         f"and {y.tolist()}")
    if np.any(np.diff(x) <= 0.0):
        raise ValueError(f"{what}: the {names[0]} must be strictly increasing, got "
                         f"{x.tolist()}")
    if np.any(np.diff(y) < 0.0):
        raise ValueError(f"{what}: the {names[1]} must be non-decreasing in the "
                         f"{names[0]} (a monotone characteristic), got {y.tolist()}")
    return x, y


def monotone_slopes(x, y) -> np.ndarray:
    """Fritsch-Carlson slopes (m,) of the table x (m,) strictly increasing, y (m,):
    scipy's PCHIP slopes (two points: the secant at both)."""
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    h = np.diff(x)
    delta = np.diff(y) / h
    if x.size == 2:
        return np.array([delta[0], delta[0]])
    w1, w2 = 2.0 * h[1:] + h[:-1], h[1:] + 2.0 * h[:-1]
    same = np.sign(delta[:-1]) * np.sign(delta[1:]) > 0.0
    # A zero secant gets no harmonic mean: divide by 1 there instead.
    left, right = np.where(same, delta[:-1], 1.0), np.where(same, delta[1:], 1.0)
    harmonic = (w1 + w2) / (w1 / left + w2 / right)
    slopes = np.zeros_like(x)
    slopes[1:-1] = np.where(same, harmonic, 0.0)

    def end(h0, h1, d0, d1):
        d = ((2.0 * h0 + h1) * d0 - h0 * d1) / (h0 + h1)
        if np.sign(d) != np.sign(d0):
            return 0.0
        if np.sign(d0) != np.sign(d1) and abs(d) > abs(3.0 * d0):
            return 3.0 * d0
        return d

    slopes[0] = end(h[0], h[1], delta[0], delta[1])
    slopes[-1] = end(h[-1], h[-2], delta[-1], delta[-2])
    return slopes


def extend_table(x, y, d, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The table (x, y, d) lengthened to m points by points on its last end line
    (spaced by the table's span, slope d_end): the interpolant does not change, so
    tables of different lengths can share one array shape."""
    x, y, d = (np.asarray(v, dtype=np.float64) for v in (x, y, d))
    extra = x[-1] + (x[-1] - x[0]) * np.arange(1, m - x.size + 1)
    return (np.concatenate([x, extra]),
            np.concatenate([y, y[-1] + d[-1] * (extra - x[-1])]),
            np.concatenate([d, np.full(extra.shape, d[-1])]))


def interval(x, u):
    """One-hot (m-1,) in x's dtype of the interval [x_i, x_i+1] of the points x (m,)
    that holds the scalar u: the last i with x_i <= u, the first or last interval
    beyond the ends."""
    i = jnp.sum(u >= x[1:-1])  # interval index in [0, m - 2]
    return (jnp.arange(x.shape[0] - 1) == i).astype(x.dtype)


def value_and_integral(x, y, d, u):
    """(f(u), integral of f from x_0 to u) of the table's interpolant at the scalar u;
    x, y, d (m,) the points, values and slopes (module docstring)."""
    pick = interval(x, u)
    x0, x1 = jnp.sum(pick * x[:-1]), jnp.sum(pick * x[1:])
    y0, y1 = jnp.sum(pick * y[:-1]), jnp.sum(pick * y[1:])
    d0, d1 = jnp.sum(pick * d[:-1]), jnp.sum(pick * d[1:])
    h = x1 - x0
    # Where, not clip: at u on an end point clip's derivative is split between its
    # branches; here the point counts as inside, where the slope is the same.
    below, above = u < x[0], u > x[-1]
    inside = jnp.where(below, x[0], jnp.where(above, x[-1], u))
    t = (inside - x0) / h
    t2, t3 = t * t, t * t * t
    t4 = t2 * t2
    value = ((2.0 * t3 - 3.0 * t2 + 1.0) * y0 + (t3 - 2.0 * t2 + t) * h * d0
             + (3.0 * t2 - 2.0 * t3) * y1 + (t3 - t2) * h * d1)
    partial = h * ((0.5 * t4 - t3 + t) * y0
                   + (0.25 * t4 - 2.0 * t3 / 3.0 + 0.5 * t2) * h * d0
                   + (t3 - 0.5 * t4) * y1 + (0.25 * t4 - t3 / 3.0) * h * d1)
    hk = x[1:] - x[:-1]
    whole = hk * (0.5 * (y[:-1] + y[1:]) + hk * (d[:-1] - d[1:]) / 12.0)
    before = jnp.sum(pick * (jnp.cumsum(whole) - whole))  # intervals 0 .. i-1
    # Past an end, the end's line: e is the distance beyond it (0 inside the table).
    e = u - inside
    slope = jnp.where(below, d[0], d[-1])
    return value + slope * e, before + partial + (value + 0.5 * slope * e) * e
