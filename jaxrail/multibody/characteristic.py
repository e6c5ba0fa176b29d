"""Nonlinear characteristics from tables: monotone, C1, exact at the table's points.

A suspension element's characteristic (a damper's force against velocity, a bump
stop's force against deflection) is given as a table of points. It is interpolated by
the monotone cubic Hermite interpolant of Fritsch and Carlson (SIAM J. Numer. Anal. 17
(1980) 238-246; the slopes of scipy's ``PchipInterpolator``): it passes through every
point, is continuously differentiable, and keeps the table's monotonicity, so a damper
never pushes the wrong way between two points. Beyond the ends it continues along the
end slopes (linear extrapolation).

The slopes are made once in numpy when the element is built; evaluating the
interpolant is a handful of traced operations, differentiable in the argument and in
the table's values and slopes (the slopes stay what they were made from: a gradient
in the table's values holds the slopes fixed).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float


def monotone_slopes(x, y) -> np.ndarray:
    """Fritsch-Carlson slopes (m,) at the points of a table x (m,) strictly increasing,
    y (m,) (the three-point formula at the ends, as scipy's PCHIP)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    h = np.diff(x)
    delta = np.diff(y) / h
    if x.size == 2:
        return np.array([delta[0], delta[0]])
    slopes = np.zeros_like(x)
    w1, w2 = 2.0 * h[1:] + h[:-1], h[1:] + 2.0 * h[:-1]
    same = (np.sign(delta[:-1]) * np.sign(delta[1:])) > 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        harmonic = (w1 + w2) / (w1 / delta[:-1] + w2 / delta[1:])
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


def check_table(x, y, what: str, increasing: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) as float arrays: ValueError naming ``what`` unless there are at least two
    finite points, x strictly increasing and (``increasing``) y strictly increasing."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.ndim != 1 or x.shape != y.shape or x.size < 2:
        raise ValueError(f"{what}: a table needs two columns of equal length >= 2, got "
                         f"shapes {x.shape} and {y.shape}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError(f"{what}: the table's values must be finite")
    if np.any(np.diff(x) <= 0.0):
        raise ValueError(f"{what}: the table's first column must be strictly increasing, "
                         f"got {x.tolist()}")
    if increasing and np.any(np.diff(y) <= 0.0):
        raise ValueError(f"{what}: the table's second column must be strictly increasing "
                         f"(a monotone characteristic), got {y.tolist()}")
    return x, y


class Characteristic(eqx.Module):
    """A tabulated characteristic y(x): points x (m,), values y (m,) and Fritsch-Carlson
    slopes (m,), as traced arrays (units those of the table)."""

    x: Float[Array, " m"]
    y: Float[Array, " m"]
    slope: Float[Array, " m"]

    @staticmethod
    def of(x, y) -> "Characteristic":
        """The characteristic through the points (x, y) (x strictly increasing)."""
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        return Characteristic(jnp.asarray(x, jnp.float64), jnp.asarray(y, jnp.float64),
                              jnp.asarray(monotone_slopes(x, y), jnp.float64))


def interpolate(c: Characteristic, x) -> Array:
    """y(x) of ``c`` at the scalar ``x``: the Hermite cubic of the interval, or the end
    slopes' lines beyond the table."""
    m = c.x.shape[0]
    i = jnp.clip(jnp.searchsorted(c.x, x, side="right") - 1, 0, m - 2)
    x0, x1, y0, y1 = c.x[i], c.x[i + 1], c.y[i], c.y[i + 1]
    d0, d1 = c.slope[i], c.slope[i + 1]
    h = x1 - x0
    t = (x - x0) / h
    t2, t3 = t * t, t * t * t
    inside = ((2 * t3 - 3 * t2 + 1) * y0 + (t3 - 2 * t2 + t) * h * d0
              + (-2 * t3 + 3 * t2) * y1 + (t3 - t2) * h * d1)
    below = c.y[0] + c.slope[0] * (x - c.x[0])
    above = c.y[-1] + c.slope[-1] * (x - c.x[-1])
    return jnp.where(x < c.x[0], below, jnp.where(x > c.x[-1], above, inside))
