"""The table spring: a nonlinear force-displacement characteristic with clearance.

The element acts along axis_i (body i's frame, normalised; it turns with body i). Its
deformation coordinate is the separation of its points along that axis,

    s = a_i . (r_Pj - r_Pi),  a_i = A_i axis_i / |axis_i|,

(the bump stop's coordinate, ``forces._bump_coords``): 0 where the points meet, so the
table's displacement is measured from there. With the clearance c >= 0 the table T
applies to the deflection past the gap,

    u = s - c  (s > c),   0  (|s| <= c),   s + c  (s < -c),
    F = T(u) + c_d sdot   (tension positive: s > 0 pulls point_j back along -a_i),
    V = integral of T from 0 to u.

T is the monotone cubic Hermite interpolant of the table (`pchip`: exact at the table's
points, C1, monotone, continued along its end slopes' lines beyond the ends) and V its
exact integral, so a conservative system keeps its energy. With c > 0 the table must
pass through (0, 0) (checked): the force is then 0 throughout the gap and continuous at
its edges. With c = 0, u = s and T(0) may be non-zero (a preload).

This covers bump stops with a nonlinear characteristic and clearance (a one-sided stop:
forces 0 for every negative displacement of the table; both stops of a lateral gap: one
table through (0, 0) with negative forces for negative displacements), progressive
rubber springs and any stiffening spring. The damping c_d [N s/m] acts at every s, in
and out of the gap (set it 0 for a stop; `BumpStop` has contact-only damping).
"""

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import pchip
from ._values import checked_axis, checked_scalar, element_label, float64_array, point_arrays


@dataclasses.dataclass(frozen=True)
class TableSpring:
    """Spring with a tabulated characteristic and clearance along axis_i (module
    docstring).

    axis_i (3,): direction of action in body i's frame (normalised when built).
    displacements (m,) [m], strictly increasing; forces (m,) [N], non-decreasing
    (tension positive); m >= 2. clearance [m] >= 0: the gap either side of s = 0 in
    which no force acts (then the table must contain the point (0, 0)). damping
    [N s/m]: linear, at every s.
    """

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    axis_i: object
    displacements: object
    forces: object
    clearance: float = 0.0
    damping: float = 0.0
    name: str = ""
    kind: ClassVar[str] = "table_spring"


class TableSpringParams(eqx.Module):
    """(k, 3) points [m] and axis; (k,) clearance [m], damping [N s/m]; (k, m) the
    tables: displacement [m], force [N] and the Fritsch-Carlson slope [N/m] at each
    point. Tables shorter than the longest are lengthened along their end line
    (`pchip.extend_table`), which leaves the characteristic unchanged; a gradient in
    ``force`` holds ``slope`` fixed, and past a lengthened table's last point it falls
    on the added points."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    axis_i: Float[Array, "k 3"]
    clearance: Float[Array, " k"]
    damping: Float[Array, " k"]
    displacement: Float[Array, "k m"]
    force: Float[Array, "k m"]
    slope: Float[Array, "k m"]


def _deflection(s, e):
    """u: the deflection past the clearance (0 inside the gap). Written with where:
    with c = 0, du/ds is 1 at s = 0 too (clip would split it there)."""
    return jnp.where(jnp.abs(s) >= e.clearance, s - e.clearance * jnp.sign(s), 0.0)


def law(s, sdot, e):
    """F (1,) [N] of one element at s (1,) [m], sdot (1,) [m/s]."""
    force, _ = pchip.value_and_integral(e.displacement, e.force, e.slope,
                                        _deflection(s[0], e))
    return (force + e.damping * sdot[0])[None]


def potential(s, e):
    """V [J]: the integral of T from 0 to the deflection u (exact, `pchip`)."""
    _, at_u = pchip.value_and_integral(e.displacement, e.force, e.slope,
                                       _deflection(s[0], e))
    _, at_0 = pchip.value_and_integral(e.displacement, e.force, e.slope,
                                       jnp.zeros_like(s[0]))
    return at_u - at_0


def power(s, sdot, e):
    """Dissipated power [W]: c_d sdot^2."""
    return jnp.sum(e.damping * sdot**2)


def _element_table(spec, what):
    x, y = pchip.check_table(spec.displacements, spec.forces, what)
    if spec.clearance > 0.0 and not np.any((x == 0.0) & (y == 0.0)):
        raise ValueError(f"{what}: with a clearance ({spec.clearance} m) the table must "
                         f"contain the point (0, 0), so that no force acts in the gap; "
                         f"got displacements {x.tolist()} and forces {y.tolist()}")
    return x, y, pchip.monotone_slopes(x, y)


def params(specs, what) -> TableSpringParams:
    """Checks the descriptions and makes their traced parameters; ValueError naming
    the element for a bad table, clearance, damping or axis."""
    tables, axes = [], []
    for n, spec in enumerate(specs):
        label = element_label(what, spec, n)
        checked_scalar(spec.clearance, f"{label}: clearance")
        checked_scalar(spec.damping, f"{label}: damping")
        axes.append(checked_axis(spec.axis_i, f"{label}: axis_i"))
        tables.append(_element_table(spec, label))
    m = max(x.size for x, _, _ in tables)
    x, y, d = zip(*(pchip.extend_table(*t, m) for t in tables))
    return TableSpringParams(
        **point_arrays(specs),
        axis_i=float64_array(axes),
        clearance=float64_array([s.clearance for s in specs]),
        damping=float64_array([s.damping for s in specs]),
        displacement=float64_array(x),
        force=float64_array(y),
        slope=float64_array(d),
    )
