"""The paper's simplified S1002: tread and flange as two separate surfaces.

The real S1002 joins tread and flange through a concave throat (sections C and D,
S = -26 .. -38.43 mm). The simplified profile removes that throat and keeps two
surfaces. Each is searched for contact on its own:

- **tread**: S1002 sections A and B (S = +60 .. -26 mm), continued beyond S = -26 by
  the tangent line of B there (slope dF/dS = -0.2417, i.e. 13.6 degrees);
- **flange**: the 70-degree flank line of section E, continued toward the tread beyond
  S = -38.4267, then sections F, G and H as in S1002.

The two continued surfaces cross at ``S_x`` (:data:`SPLIT_MM` = -35.9303 mm, F = 5.141 mm,
from the closed-form intersection of the two lines). The tread's domain is
``[S_x, 60]`` mm and the flange's is ``[-69.5, S_x]`` mm. Side by side they form a sharp
V, 2.67 mm deeper than the real throat at S_x. A rail gauge corner that sits in the
throat touches both flanks of the V: this is the paper's two-point contact.

Curvature (wheel ``F''``, positive = concave as seen from the rail). The flange surface
has ``F'' <= 0`` everywhere: the line E has zero curvature, and the arcs F, G, H are convex
with radii 20, 12 and 20.5 mm. The tread keeps the hollow of the S1002 polynomial: ``F'' > 0``
for S < +14.08 mm, where the slope magnitude |dF/dS| is smallest (0.0087). The concave
radius grows from 51.8 mm at S = -26 to 320 mm at S = 0 and is infinite at +14.08. On
[+14.08, +32.16] the tread is convex, with radius >= 196.5 mm (smallest at S = +28.8).
Sections A and the continuation line are straight.
"""

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._float64 import require_float64
from ._base import ClosedFormProfile, WheelProfile
from .s1002 import (
    _AE,
    _B_POLY,
    _BE,
    S1002_DOMAIN,
    SECTION_JOINTS_MM,
    SECTION_ROWS,
    _row,
    height_derivatives_from_mm,
    piecewise_derivatives_mm,
)

_AB_JOINT, _TREAD_END, _, _FLANK_TOP, _EF_JOINT, _FG_JOINT, _GH_JOINT = SECTION_JOINTS_MM

# Tangent of section B at S = -26 mm (value [mm] and slope [-]).
_B = np.polynomial.Polynomial(_B_POLY)
_TREAD_END_HEIGHT = float(_B(_TREAD_END))
_TREAD_END_SLOPE = float(_B.deriv()(_TREAD_END))

# Tread tangent line = flank line E:  F26 + k (S + 26) = -AE - BE S.
SPLIT_MM = float((-_AE - _TREAD_END_HEIGHT + _TREAD_END_SLOPE * _TREAD_END)
                 / (_TREAD_END_SLOPE + _BE))

TREAD_DOMAIN = (1e-3 * SPLIT_MM, S1002_DOMAIN[1])
FLANGE_DOMAIN = (S1002_DOMAIN[0], 1e-3 * SPLIT_MM)

# Sections in increasing S. The tread: tangent line, B, A. The flange: H, G, F, and E,
# which runs on past its S1002 end toward the tread.
_TANGENT_ROW = _row((_TREAD_END_HEIGHT - _TREAD_END_SLOPE * _TREAD_END, _TREAD_END_SLOPE))
_TREAD_ROWS = (_TANGENT_ROW, SECTION_ROWS["B"], SECTION_ROWS["A"])
_TREAD_JOINTS = (_TREAD_END, _AB_JOINT)
_FLANGE_ROWS = tuple(SECTION_ROWS[k] for k in "HGFE")
_FLANGE_JOINTS = (_GH_JOINT, _FG_JOINT, _EF_JOINT)


def _tread_mm(s):
    return piecewise_derivatives_mm(s, _TREAD_JOINTS, _TREAD_ROWS)


def _flange_mm(s):
    return piecewise_derivatives_mm(s, _FLANGE_JOINTS, _FLANGE_ROWS)


class SimplifiedTread(ClosedFormProfile):
    """Tread surface of the simplified S1002 over ``[S_x, 0.060]`` m (module docstring)."""

    def __init__(self):
        require_float64("SimplifiedTread")

    @property
    def domain(self) -> tuple[float, float]:
        return TREAD_DOMAIN

    def height_derivatives(self, y: Float[ArrayLike, ""]) -> tuple[Array, Array, Array]:
        return height_derivatives_from_mm(_tread_mm, y)


class SimplifiedFlange(ClosedFormProfile):
    """Flange surface of the simplified S1002 over ``[-0.0695, S_x]`` m (module docstring)."""

    def __init__(self):
        require_float64("SimplifiedFlange")

    @property
    def domain(self) -> tuple[float, float]:
        return FLANGE_DOMAIN

    def height_derivatives(self, y: Float[ArrayLike, ""]) -> tuple[Array, Array, Array]:
        return height_derivatives_from_mm(_flange_mm, y)


def simplified_s1002(nominal_radius: float = 0.46) -> WheelProfile:
    """The paper's simplified S1002 wheel: ``surfaces = (tread, flange)``, each searched
    for at most one contact patch, with rolling radius ``nominal_radius`` [m] at the
    taping line."""
    require_float64("simplified_s1002")
    if not (np.isfinite(nominal_radius) and nominal_radius > 0.0):
        raise ValueError(f"nominal_radius must be a positive length in m, got {nominal_radius}")
    return WheelProfile(
        surfaces=(SimplifiedTread(), SimplifiedFlange()),
        nominal_radius=jnp.asarray(nominal_radius, dtype=jnp.float64),
        name="S1002-simplified",
    )
