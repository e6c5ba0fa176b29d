"""Force elements with a spring and a damper in series: each has an internal state.

**maxwell_damper** (1 internal state): a hydraulic damper in series with its mounting
stiffness (rubber end bushes, oil compressibility), the Maxwell element. Railway
vehicles' yaw dampers, lateral and vertical dampers are written so: the series
stiffness k_s is what makes a yaw damper stiffen the bogie against yaw at hunting
frequencies and so sets a coach's critical speed. Along the line between its two
points (length s [m], free length L0 [m]), with the damper's own extension z [m]:

    F = k_s (s - L0 - z)   (tension positive),      zdot = v(F),

v(F) the damper's velocity at force F: its force-velocity characteristic, given as a
table (blow-off: a steep slope up to the relief force, a shallow one beyond), read as
velocity against force and interpolated monotonically (:mod:`.pchip`: exact at the
table's points), or linear, v = F / c. Stored energy k_s (s - L0 - z)^2 / 2; dissipated power F v(F).
Under a sinusoid s = L0 + x0 sin(w t) its force tends to that of the complex stiffness
K(w) = k_s i w c / (k_s + i w c) (linear damper).

**air_spring** (1 internal state): an air spring after the three-element model of
Nishimura (air spring on a reservoir through an orifice) as used by Docquier, Fisette
and Jeanmart, Vehicle System Dynamics 45 (2007) 505-524, and the linearised form of
Berg, Vehicle System Dynamics 33 (1999) suppl. 528-539 [R: recalled, not checked
against the papers]. Vertically a spring k1 (the bellows' effective-area and volume
stiffness) in parallel with the reservoir's volume stiffness k2 in series with the
orifice's damping c; laterally and longitudinally the bellows' shear stiffness. In
the frame of body i at point_i, with the deflection u = A_i^T (r_Pj - r_Pi) [m] (both
points coincide at zero deflection) and the orifice state z [m]:

    F = (k_x u_x, k_y u_y, F0 + k1 u_z + k2 (u_z - z)),   zdot = k2 (u_z - z) / c,

F0 [N] the static load it carries at zero deflection (same sign as K u: negative
pushes body j up, as a bushing's preload). Vertical complex stiffness
K(w) = k1 + k2 i w c / (k2 + i w c): k1 at low frequency, k1 + k2 at high, the
reservoir's frequency dependence. Stored energy k_x u_x^2/2 + k_y u_y^2/2 + F0 u_z +
k1 u_z^2/2 + k2 (u_z - z)^2/2; dissipated power c zdot^2.
"""

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import quaternion as qt
from ._values import checked_scalar, element_label, float64_array, point_arrays
from .element_geometry import line_length, separation
from .pchip import check_table, extend_table, monotone_slopes, value_and_integral


@dataclasses.dataclass(frozen=True)
class MaxwellDamper:
    """A damper in series with its mounting stiffness, between point_i of body i and
    point_j of body j (module docstring).

    series_stiffness k_s [N/m]; free_length L0 [m]; damping c [N s/m] (linear), or a
    force-velocity characteristic: ``velocities`` [m/s] strictly increasing and
    ``forces`` [N] strictly increasing (extension and tension positive; it should
    pass through (0, 0)); it replaces ``damping``.
    """

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    series_stiffness: float
    free_length: float
    damping: float = 0.0
    velocities: object = None
    forces: object = None
    name: str = ""
    kind: ClassVar[str] = "maxwell_damper"


@dataclasses.dataclass(frozen=True)
class AirSpring:
    """An air spring between point_i of body i and point_j of body j, axes those of body
    i (module docstring): vertical_stiffness k1, reservoir_stiffness k2 [N/m],
    orifice_damping c [N s/m], lateral_stiffness k_y and longitudinal_stiffness k_x
    [N/m], preload F0 [N] (vertical, at zero deflection)."""

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    vertical_stiffness: float
    reservoir_stiffness: float
    orifice_damping: float
    lateral_stiffness: float
    longitudinal_stiffness: float
    preload: float = 0.0
    name: str = ""
    kind: ClassVar[str] = "air_spring"


class MaxwellDamperParams(eqx.Module):
    """(k, 3) points [m]; (k,) series stiffness [N/m] and free length [m]; the damper's
    velocity against force: (k, m) forces [N], velocities [m/s] and the interpolant's
    slopes [m/(N s)] (:mod:`.pchip`)."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    series_stiffness: Float[Array, " k"]
    free_length: Float[Array, " k"]
    forces: Float[Array, "k m"]
    velocities: Float[Array, "k m"]
    slopes: Float[Array, "k m"]


class AirSpringParams(eqx.Module):
    """(k, 3) points [m]; (k,) stiffnesses [N/m], orifice damping [N s/m], preload [N]."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    vertical_stiffness: Float[Array, " k"]
    reservoir_stiffness: Float[Array, " k"]
    orifice_damping: Float[Array, " k"]
    lateral_stiffness: Float[Array, " k"]
    longitudinal_stiffness: Float[Array, " k"]
    preload: Float[Array, " k"]


def _positive(specs, what, name):
    """The field ``name`` of each element, each checked > 0 (the error names it)."""
    return [checked_scalar(getattr(s, name), f"{element_label(what, s, n)} {name}",
                           positive=True) for n, s in enumerate(specs)]


# ---- the Maxwell damper ----------------------------------------------------------


def _maxwell_coords(qi, qj, e):
    return line_length(qi, qj, e)


def _maxwell_force(s, e, z):
    return e.series_stiffness * (s - e.free_length - z)


def _maxwell_law(s, sdot, e, z):
    return _maxwell_force(s, e, z)


def _maxwell_rate(s, sdot, e, z):
    force = _maxwell_force(s, e, z)[0]
    return value_and_integral(e.forces, e.velocities, e.slopes, force)[0][None]


def _maxwell_initial(s, e):
    return s - e.free_length


def _maxwell_potential(s, e, z):
    return 0.5 * e.series_stiffness * jnp.sum((s - e.free_length - z) ** 2)


def _maxwell_power(s, sdot, e, z):
    return jnp.sum(_maxwell_force(s, e, z) * _maxwell_rate(s, sdot, e, z))


def _damper_table(spec, what):
    """(forces, velocities) of one damper: its characteristic, or the linear one."""
    if spec.velocities is None and spec.forces is None:
        c = checked_scalar(spec.damping, f"{what} damping", positive=True)
        return np.array([-1.0, 1.0]) * c, np.array([-1.0, 1.0])
    if spec.velocities is None or spec.forces is None:
        raise ValueError(f"{what}: a characteristic needs both velocities and forces")
    f, v = check_table(spec.forces, spec.velocities, f"{what} characteristic",
                       ("forces", "velocities"))
    return f, v


def _maxwell_params(specs, what):
    tables = [_damper_table(s, f"{what} {s.name!r}") for s in specs]
    size = max(len(f) for f, _ in tables)
    columns = [extend_table(f, v, monotone_slopes(f, v), size) for f, v in tables]
    f, v, m = (float64_array(np.stack(c)) for c in zip(*columns))
    return MaxwellDamperParams(
        **point_arrays(specs),
        series_stiffness=float64_array(_positive(specs, what, "series_stiffness")),
        free_length=float64_array([s.free_length for s in specs]),
        forces=f, velocities=v, slopes=m,
    )


# ---- the air spring --------------------------------------------------------------


def _air_coords(qi, qj, e):
    a_i, _, d = separation(qi, qj, e)
    return qt.matvec(a_i.T, d)


def _air_law(s, sdot, e, z):
    vertical = e.preload + e.vertical_stiffness * s[2] + e.reservoir_stiffness * (s[2] - z[0])
    return jnp.stack([e.longitudinal_stiffness * s[0], e.lateral_stiffness * s[1], vertical])


def _air_rate(s, sdot, e, z):
    return (e.reservoir_stiffness * (s[2] - z[0]) / e.orifice_damping)[None]


def _air_initial(s, e):
    return s[2:3]


def _air_potential(s, e, z):
    return (0.5 * e.longitudinal_stiffness * s[0] ** 2 + 0.5 * e.lateral_stiffness * s[1] ** 2
            + e.preload * s[2] + 0.5 * e.vertical_stiffness * s[2] ** 2
            + 0.5 * e.reservoir_stiffness * (s[2] - z[0]) ** 2)


def _air_power(s, sdot, e, z):
    return e.orifice_damping * _air_rate(s, sdot, e, z)[0] ** 2


def _air_params(specs, what):
    def positive(name):
        return float64_array(_positive(specs, what, name))

    return AirSpringParams(
        **point_arrays(specs),
        vertical_stiffness=positive("vertical_stiffness"),
        reservoir_stiffness=positive("reservoir_stiffness"),
        orifice_damping=positive("orifice_damping"),
        lateral_stiffness=positive("lateral_stiffness"),
        longitudinal_stiffness=positive("longitudinal_stiffness"),
        preload=float64_array([s.preload for s in specs]),
    )


def series_kinds(force_kind):
    """The FORCE_KINDS entries of this module, made with the ``ForceKind`` class."""
    return {
        "maxwell_damper": force_kind(_maxwell_coords, _maxwell_law, _maxwell_potential,
                                     _maxwell_params, _maxwell_power, 1, _maxwell_rate,
                                     _maxwell_initial),
        "air_spring": force_kind(_air_coords, _air_law, _air_potential, _air_params,
                                 _air_power, 1, _air_rate, _air_initial),
    }
