"""The one range check of user-given numbers (scenarios, the command line, named
parameters, Monte Carlo draws), so that every such error reads the same."""

import math


def within(value, low: float, high: float, unit: str, label: str) -> float:
    """``value`` as a float if it is finite and within ``[low, high]``, else ValueError
    ``"<label> must be within [low, high] <unit>, got <value>"``."""
    value = float(value)
    if not math.isfinite(value) or not low <= value <= high:
        raise ValueError(f"{label} must be within [{low:g}, {high:g}] {unit}, got {value!r}")
    return value
