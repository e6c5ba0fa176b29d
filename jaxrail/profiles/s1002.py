"""The S1002 wheel profile (EN 13715 / UIC 510-2), from its piecewise section table.

The standard writes the profile as ``F(S)`` [mm]: ``S`` is the lateral coordinate from
the taping line, positive toward the outer (field-side) face, so the flange is at
``S < 0`` and the back of the flange at ``S = -70``; ``F`` is the height radially
outward from the taping-line circle (``F(0) = 0``, flange tip ``F(-55) = 28``). That is
exactly the convention of :mod:`jaxrail.profiles._base` with ``y = S / 1000`` [m] and
``height = F / 1000`` [m].

Sections, from the field side to the flange back (coefficients as tabulated by H. Netter,
DLR; they reproduce the Manchester benchmark ``MBench_S1002_v3.prw`` to 1.6e-6 mm):

=======  ======================  ==============================================
section  S range [mm]            shape
=======  ======================  ==============================================
A        +60 .. +32.15796        straight 1:15 outer chamfer
B        +32.15796 .. -26        tread, polynomial of degree 8
C        -26 .. -35              start of the throat, polynomial of degree 7
D        -35 .. -38.426669071    throat fillet, R13, concave
E        .. -39.764473993        flange flank, straight, 70 degrees
F        .. -49.662510381        flange face, R20
G        .. -62.764705882        flange tip, R12, top at F(-55) = 28
H        .. -70                  flange back, R20.5, vertical at S = -70
=======  ======================  ==============================================

Smoothing: the tabulated coefficients are rounded. As a result the profile jumps by
1.2e-4 mm at S = -35 and by 3.7e-5 mm at S = -26, and the slope jumps by about 1e-5
at the same places. Here section C gets a quintic correction polynomial. The corrected C
meets B (at -26) and D (at -35) with equal height and slope. The correction has zero
second derivative at both ends, so the curvature at the joints is that of the table. It
changes F by at most 1.2e-4 mm (it is largest next to S = -35). The other joints already
match to < 7e-8 mm in height and < 1e-8 in slope.

Domain: ``(-0.0695, 0.060)`` m. At S = -70 the flange back is vertical (infinite slope),
so the domain stops 0.5 mm short of it, where the slope is 4.4. Outside the domain the
end sections go on (section A is a straight line; section H is clipped where its circle
ends), so values there are finite but are not the standard profile.
"""

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._float64 import require_float64
from ..compilation import computed_once
from ._base import ClosedFormProfile, WheelProfile

# Section table, mm (profiles.md section 1.2; signs as in the formulas there).
_AA, _BA = 1.364323640, 0.066666667
# F_B = sum_k B[k] S^k (signs of the table folded in)
_B_POLY = (0.0, -3.358537058e-02, 1.565681624e-03, -2.810427944e-05, 5.844240864e-08,
           -1.562379023e-08, 5.309217349e-15, -5.957839843e-12, 2.646656573e-13)
_C_POLY = (-4.320221063e+03, -1.038384026e+03, -1.065501873e+02, -6.051367875,
           -2.054332446e-01, -4.169739389e-03, -4.687195829e-05, -2.252755540e-07)
_AD, _BD, _CD = 16.446, 13.0, 26.210665
_AE, _BE = 93.576667419, 2.747477419
_AF, _BF, _CF = 8.834924130, 20.0, 58.558326413
_AG, _BG, _CG = 16.0, 12.0, 55.0
_AH, _BH, _CH = 9.519259302, 20.5, 49.5

# Section joints [mm], field side first: A|B, B|C, C|D, D|E, E|F, F|G, G|H.
SECTION_JOINTS_MM = (32.15796, -26.0, -35.0, -38.426669071, -39.764473993,
                     -49.662510381, -62.764705882)
FLANGE_BACK_MM = -70.0
S1002_DOMAIN = (-0.0695, 0.060)

# Smallest argument a square root is allowed to see [mm^2]. A section's formula is only
# evaluated with that section's coefficients, but a circle is also evaluated beyond its own
# ends outside the domain (and a line section carries a zero-weight circle term). The
# floor keeps values and derivatives finite there. Inside its own range every arc has an
# argument >= 20 mm^2, so the floor never changes a value in the domain.
_SQRT_FLOOR = 1e-12


def _c_correction_coefficients() -> np.ndarray:
    """Quintic p(S) added to section C so that it meets D at S = -35 and B at S = -26 in
    value and slope, with p'' = 0 at both ends. Monomial coefficients in S (numpy, at
    import), from the Hermite conditions written in t = (S + 35)/9 for conditioning."""
    b_poly = np.polynomial.Polynomial(_B_POLY)
    c_poly = np.polynomial.Polynomial(_C_POLY)
    s0, s1 = -35.0, -26.0
    length = s1 - s0
    u = s0 + _CD
    root = np.sqrt(_BD**2 - u**2)
    d_value, d_slope = _AD - root, u / root
    # Targets in t: value and dp/dt = length * dp/dS.
    rhs = np.array([
        d_value - c_poly(s0), length * (d_slope - c_poly.deriv()(s0)), 0.0,
        b_poly(s1) - c_poly(s1), length * (b_poly.deriv()(s1) - c_poly.deriv()(s1)), 0.0,
    ])
    rows = []
    for t in (0.0, 1.0):
        rows.append([t**k for k in range(6)])
        rows.append([k * t ** (k - 1) if k >= 1 else 0.0 for k in range(6)])
        rows.append([k * (k - 1) * t ** (k - 2) if k >= 2 else 0.0 for k in range(6)])
    in_t = np.polynomial.Polynomial(np.linalg.solve(np.array(rows), rhs))
    # p(S) = p_t((S - s0) / length)
    return in_t(np.polynomial.Polynomial([-s0 / length, 1.0 / length])).coef


_C_CORRECTION = _c_correction_coefficients()

# Every section is written as  F = polynomial(S) + w * sqrt(r^2 - (S + c)^2)  [mm], one row
# per section, so that the height is one Horner evaluation and one square root with the
# row picked by the section index (cheap to compile, no branch to differentiate).
_DEGREE = len(_B_POLY) - 1


def _row(poly=(0.0,), weight=0.0, radius=0.0, centre=0.0):
    padded = np.zeros(_DEGREE + 1)
    padded[: len(poly)] = poly
    return padded, (weight, radius**2, centre)


SECTION_ROWS = {
    "A": _row((_AA, -_BA)),
    "B": _row(_B_POLY),
    "C": _row(np.polynomial.polynomial.polyadd(_C_POLY, _C_CORRECTION)),
    "D": _row((_AD,), -1.0, _BD, _CD),
    "E": _row((-_AE, -_BE)),
    "F": _row((_AF,), 1.0, _BF, _CF),
    "G": _row((_AG,), 1.0, _BG, _CG),
    "H": _row((_AH,), 1.0, _BH, _CH),
}


def piecewise_derivatives_mm(s, joints_ascending, rows):
    """Height [mm], slope [-] and second derivative [1/mm] at ``s`` [mm] of a profile
    made of ``rows`` (section rows in increasing S) separated by ``joints_ascending``
    [mm], in closed form. At a joint the lower section is used; the sections meet there
    in value and slope, so the choice does not matter."""
    poly = jnp.asarray(np.stack([r[0] for r in rows]), dtype=jnp.float64)
    arc = jnp.asarray(np.stack([r[1] for r in rows]), dtype=jnp.float64)
    # the count of joints below s (searchsorted's left side) without its while loop
    index = jnp.sum(jnp.asarray(joints_ascending, dtype=jnp.float64) < s)
    coefficients, (weight, radius_sq, centre) = poly[index], arc[index]
    # Horner's scheme for the polynomial and its first two derivatives at once.
    value, first, second = coefficients[_DEGREE], 0.0, 0.0
    for k in range(_DEGREE - 1, -1, -1):
        second = second * s + first
        first = first * s + value
        value = value * s + coefficients[k]
    # The arc: w sqrt(A), A = r^2 - (s + c)^2; constant where A is at its floor.
    offset = s + centre
    argument = radius_sq - offset**2
    on_arc = argument > _SQRT_FLOOR
    root = jnp.sqrt(jnp.where(on_arc, argument, _SQRT_FLOOR))
    arc_slope = jnp.where(on_arc, -offset / root, 0.0)
    arc_second = jnp.where(on_arc, -radius_sq / (root * root * root), 0.0)
    return computed_once(value + weight * root, first + weight * arc_slope,
                         2.0 * second + weight * arc_second)


def height_derivatives_from_mm(derivatives_mm, y):
    """``(height [m], slope [-], second derivative [1/m])`` at ``y`` [m] of a profile
    whose ``derivatives_mm(s)`` works in mm."""
    f, f1, f2 = derivatives_mm(1e3 * jnp.asarray(y, dtype=jnp.float64))
    return 1e-3 * f, f1, 1e3 * f2


# Sections in increasing S (H .. A) and the joints between them, increasing.
_ROWS_ASCENDING = tuple(SECTION_ROWS[k] for k in "HGFEDCBA")
_JOINTS_ASCENDING = tuple(sorted(SECTION_JOINTS_MM))


def s1002_derivatives_mm(s_mm: Float[ArrayLike, ""]) -> tuple[Array, Array, Array]:
    """S1002 height ``F`` [mm], ``dF/dS`` [-] and ``d^2F/dS^2`` [1/mm] at lateral
    position ``S`` [mm] (scalar), smoothed as the module docstring says. Gradients are
    finite everywhere."""
    s = jnp.asarray(s_mm, dtype=jnp.float64)
    return piecewise_derivatives_mm(s, _JOINTS_ASCENDING, _ROWS_ASCENDING)


class S1002(ClosedFormProfile):
    """The S1002 wheel profile as a :class:`Profile` over ``(-0.0695, 0.060)`` m.

    ``height(y)`` [m] is the standard's ``F`` at ``S = 1000 y`` (see the module docstring
    for sections, smoothing and domain). The shape is fixed by the standard, so the
    module has no parameters; use :class:`TabulatedProfile` for measured or worn wheels.
    """

    def __init__(self):
        require_float64("S1002")

    @property
    def domain(self) -> tuple[float, float]:
        return S1002_DOMAIN

    def height_derivatives(self, y: Float[ArrayLike, ""]) -> tuple[Array, Array, Array]:
        return height_derivatives_from_mm(s1002_derivatives_mm, y)


def s1002(nominal_radius: float = 0.46) -> WheelProfile:
    """An S1002 wheel with taping-line rolling radius ``nominal_radius`` [m] (one surface)."""
    require_float64("s1002")
    if not (np.isfinite(nominal_radius) and nominal_radius > 0.0):
        raise ValueError(f"nominal_radius must be a positive length in m, got {nominal_radius}")
    return WheelProfile(
        surfaces=(S1002(),),
        nominal_radius=jnp.asarray(nominal_radius, dtype=jnp.float64),
        name="S1002",
    )

