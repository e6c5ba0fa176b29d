"""Range checks of physical inputs given from Python: a concrete value outside its
range is a ValueError naming it; traced values (inside a compiled program) pass
unchecked, so the checks add nothing to compiled simulations."""

import jax
import numpy as np


def check_range(name, value, low, high, low_open=True):
    """ValueError if a concrete ``value`` (scalar or array) is not in (low, high] (or
    [low, high] with ``low_open=False``) or is NaN; traced values pass."""
    if value is None or isinstance(value, jax.core.Tracer):
        return
    for v in np.ravel(np.asarray(value, dtype=float)):
        too_low = v <= low if low_open else v < low
        if too_low or v > high or v != v:
            bracket = "(" if low_open else "["
            raise ValueError(f"{name} must lie in {bracket}{low}, {high}], got {v}")
