"""Units of the numbers in vehicle files: parsing, conversion to SI and dimensions.

A unit is a product of symbols with integer powers and at most one ``/``:
``"kN s/m"``, ``"N m s/rad"``, ``"t m^2"``, ``"m/s^2"``, ``"km/h"``, or ``"-"`` for a
dimensionless number. Symbols are separated by spaces, ``*`` or ``·``; a power is
written ``^2`` (or ``²``, ``³``). The symbols are those of :data:`SYMBOLS` (no free SI
prefixes: ``"mm"`` is listed, ``"mkg"`` is not).

A dimension is the tuple of the powers of (kg, m, s). Angles are dimensionless (the
radian is 1), so ``"N m/rad"`` and ``"N m"`` have the same dimension; ``"deg"`` and
``"mrad"`` still convert to radians.

Conversion keeps the exact rational scale of a unit where there is one and applies it
as ``value * numerator / denominator``, so that ``1435 mm`` becomes exactly ``1.435``,
the float a Python literal in metres gives.
"""

import math
from fractions import Fraction
from typing import NamedTuple

Dimension = tuple[int, int, int]  # powers of (kg, m, s)

_M, _L, _T = (1, 0, 0), (0, 1, 0), (0, 0, 1)
_NONE: Dimension = (0, 0, 0)
_FORCE: Dimension = (1, 1, -2)
_PRESSURE: Dimension = (1, -1, -2)

# symbol -> (scale to SI: a Fraction, or a float where it is irrational; dimension)
SYMBOLS: dict[str, tuple[Fraction | float, Dimension]] = {
    "m": (Fraction(1), _L), "mm": (Fraction(1, 1000), _L), "cm": (Fraction(1, 100), _L),
    "km": (Fraction(1000), _L),
    "kg": (Fraction(1), _M), "g": (Fraction(1, 1000), _M), "t": (Fraction(1000), _M),
    "s": (Fraction(1), _T), "ms": (Fraction(1, 1000), _T), "min": (Fraction(60), _T),
    "h": (Fraction(3600), _T),
    "N": (Fraction(1), _FORCE), "kN": (Fraction(1000), _FORCE),
    "MN": (Fraction(10**6), _FORCE),
    "J": (Fraction(1), (1, 2, -2)), "W": (Fraction(1), (1, 2, -3)),
    "rad": (Fraction(1), _NONE), "mrad": (Fraction(1, 1000), _NONE),
    "deg": (math.pi / 180.0, _NONE),
    "Hz": (Fraction(1), (0, 0, -1)),
    "Pa": (Fraction(1), _PRESSURE), "kPa": (Fraction(1000), _PRESSURE),
    "MPa": (Fraction(10**6), _PRESSURE), "GPa": (Fraction(10**9), _PRESSURE),
    "bar": (Fraction(10**5), _PRESSURE),
    "l": (Fraction(1, 1000), (0, 3, 0)), "L": (Fraction(1, 1000), (0, 3, 0)),
}

# Dimensions with a name, for messages: dimension -> (name, an example unit).
NAMES: dict[Dimension, tuple[str, str]] = {
    _NONE: ("dimensionless (or an angle)", "-"),
    _L: ("length", "m"), _M: ("mass", "kg"), _T: ("time", "s"),
    _FORCE: ("force", "N"), (1, 0, -2): ("stiffness (force per length)", "N/m"),
    (1, 0, -1): ("damping (force per velocity)", "N s/m"),
    (1, 2, -2): ("moment, energy or rotational stiffness", "N m/rad"),
    (1, 2, -1): ("rotational damping", "N m s/rad"), (1, 2, 0): ("inertia", "kg m^2"),
    (0, 0, -1): ("frequency", "Hz"), (0, 1, -1): ("velocity", "m/s"),
    (0, 1, -2): ("acceleration", "m/s^2"), _PRESSURE: ("pressure", "Pa"),
    (0, 3, 0): ("volume", "m^3"),
}

_POWERS = {"²": "^2", "³": "^3"}


class Unit(NamedTuple):
    """A parsed unit: its ``scale`` to SI (Fraction, or float if irrational) and its
    ``dimension`` (powers of kg, m, s)."""

    scale: Fraction | float
    dimension: Dimension


def describe(dimension: Dimension) -> str:
    """A dimension in words, e.g. ``"stiffness (force per length), e.g. N/m"``."""
    if dimension in NAMES:
        name, example = NAMES[dimension]
        return f"{name}, e.g. {example}"
    return "kg^{} m^{} s^{}".format(*dimension)


def _factor(text: str, unit: str) -> tuple[Fraction | float, Dimension]:
    symbol, _, power = text.partition("^")
    if symbol not in SYMBOLS:
        raise ValueError(f"unknown unit {unit!r} (symbol {symbol!r}); known symbols: "
                         f"{', '.join(SYMBOLS)}, or '-' for a dimensionless number")
    try:
        n = int(power) if power else 1
    except ValueError:
        raise ValueError(f"unit {unit!r}: the power in {text!r} must be an integer") from None
    scale, dim = SYMBOLS[symbol]
    return scale**n, tuple(n * d for d in dim)


def _product(text: str, unit: str) -> tuple[Fraction | float, Dimension]:
    scale, dim = Fraction(1), _NONE
    for token in text.replace("*", " ").replace("·", " ").split():
        s, d = _factor(token, unit)
        scale, dim = scale * s, tuple(a + b for a, b in zip(dim, d))
    return scale, dim


def parse_unit(unit) -> Unit:
    """The :class:`Unit` of a unit string; ValueError names what is wrong."""
    if not isinstance(unit, str) or not unit.strip():
        raise ValueError(f"a unit must be a non-empty string, got {unit!r}")
    text = unit.strip()
    if text == "-":
        return Unit(Fraction(1), _NONE)
    for glyph, power in _POWERS.items():
        text = text.replace(glyph, power)
    top, slash, bottom = text.partition("/")
    if "/" in bottom or (slash and not bottom.strip()):
        raise ValueError(f"unit {unit!r}: at most one '/' with symbols after it")
    scale, dim = _product(top, unit) if top.strip() not in ("", "1") else (Fraction(1), _NONE)
    if slash:
        s, d = _product(bottom, unit)
        scale, dim = scale / s, tuple(a - b for a, b in zip(dim, d))
    return Unit(scale, dim)


def to_si(value: float, unit: Unit) -> float:
    """``value`` in ``unit`` as a float in SI units (radians for angles)."""
    scale = unit.scale
    if isinstance(scale, Fraction):
        if scale == 1:
            return float(value)
        return float(value) * scale.numerator / scale.denominator
    return float(value) * scale


def dimension_of(unit: str) -> Dimension:
    """The dimension of a unit string."""
    return parse_unit(unit).dimension
