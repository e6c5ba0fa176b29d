"""Build-time checks and conversions of the numbers in multibody descriptions."""

import jax.numpy as jnp
import numpy as np


def float64_array(x):
    """``x`` as a float64 JAX array."""
    return jnp.asarray(np.asarray(x, dtype=np.float64), dtype=jnp.float64)


def checked_vector(x, shape, what):
    """``x`` as a float64 numpy array of ``shape``, or a ValueError naming ``what``."""
    a = np.asarray(x, dtype=np.float64)
    if a.shape != shape or not np.all(np.isfinite(a)):
        raise ValueError(f"{what} must be finite with shape {shape}, got {x!r}")
    return a


def checked_axis(x, what):
    """``x`` as a float64 numpy array (3,), finite and non-zero (not normalised), or a
    ValueError naming ``what``."""
    a = np.asarray(x, dtype=np.float64)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.linalg.norm(a) == 0.0:
        raise ValueError(f"{what} must be a finite non-zero 3-vector, got {x!r}")
    return a


def point_arrays(specs):
    """``{"point_i": (k, 3), "point_j": (k, 3)}`` float64 arrays [m] of the elements'
    points, as the parameters of every two-point element kind hold them."""
    return dict(point_i=float64_array([s.point_i for s in specs]),
                point_j=float64_array([s.point_j for s in specs]))


def element_label(what, spec, n):
    """How a message names element ``n`` of a kind: by its name, or by its place."""
    return f"{what} {spec.name!r}" if spec.name else f"{what} #{n}"


def checked_scalar(x, what, positive=False):
    """``x`` as a float, or a ValueError naming ``what``: finite and >= 0 (> 0 if
    ``positive``)."""
    value = float(x)
    if not (np.isfinite(value) and (value > 0.0 if positive else value >= 0.0)):
        raise ValueError(f"{what} must be {'>' if positive else '>='} 0, got {x!r}")
    return value
