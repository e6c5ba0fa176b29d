"""The friction (Coulomb) damper: a sliding contact that resists relative motion with
a force of constant magnitude, such as the friction wedges of a three-piece freight
bogie or the friction dampers of a Y25 bogie.

The element acts along axis_i (body i's frame, normalised: the direction the surfaces
slide along, which turns with body i). Its coordinate is the bump stop's,
s = a_i . (r_Pj - r_Pi) (``forces._bump_coords``), and its law

    F = F_f sdot / sqrt(sdot^2 + v_eps^2)      (tension positive, like the others)

with F_f [N] the friction force and v_eps [m/s] a regularising velocity. It stores no
energy (V = 0) and dissipates P = F sdot = F_f sdot^2 / sqrt(sdot^2 + v_eps^2) >= 0.

Why this form of Coulomb's F_f sign(sdot): it is C-infinity in sdot, odd, increasing,
and bounded by F_f, and it approaches F_f sign(sdot) once |sdot| >> v_eps (the error is
F_f v_eps^2 / (2 sdot^2)). At rest its slope is finite, F_f / v_eps: near rest the
damper is a viscous damper of that coefficient, so the force and its derivatives (the
Jacobian an implicit solver builds, the gradients of a parameter study) stay finite
and an adaptive solver meets no switch. A true sign function would chatter, and a
stick-slip switch would need events. The price: there is no sticking. Under a steady
load L < F_f the damper creeps at v_eps L / sqrt(F_f^2 - L^2), and its stiff viscous
rate F_f / (m v_eps) near rest shortens an explicit solver's steps; a larger v_eps
eases both at the cost of the loop's shape.

Loop energy: over one cycle x0 sin(omega t), Coulomb friction does 4 F_f x0. The
regularised law does 4 F_f x0 (1 - r^2 (ln(4 / r) - 1/2) / 2 + ...) with
r = v_eps / (omega x0) (the complete elliptic integrals of the exact integral, expanded
for small r; the exact value is sqrt(1 + r^2) E(m) - r^2 K(m) / sqrt(1 + r^2) times
4 F_f x0, m = 1 / (1 + r^2)): with v_eps = 1e-3 m/s a 10 mm, 2 Hz cycle (r = 0.008)
loses 0.018 % of the loop, a 1 mm one (r = 0.08) 1.1 %. Choose v_eps well below the
sliding speeds that matter.

The friction force is constant here; the load-dependent friction of a wedge (F_f
proportional to the spring force) is not modelled.
"""

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from ._values import checked_axis, checked_scalar, element_label, float64_array, point_arrays


@dataclasses.dataclass(frozen=True)
class FrictionDamper:
    """Coulomb damper along axis_i between point_i of body i and point_j of body j
    (module docstring).

    axis_i (3,): sliding direction in body i's frame (normalised when built).
    friction_force F_f [N] >= 0; velocity_scale v_eps [m/s] > 0, the regularising
    velocity (below it the damper acts as a viscous damper F_f / v_eps).
    """

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    axis_i: object
    friction_force: float
    velocity_scale: float = 1e-3
    name: str = ""
    kind: ClassVar[str] = "friction_damper"


class FrictionDamperParams(eqx.Module):
    """(k, 3) points [m] and axis; (k,) friction_force [N], velocity_scale [m/s]."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    axis_i: Float[Array, "k 3"]
    friction_force: Float[Array, " k"]
    velocity_scale: Float[Array, " k"]


def law(s, sdot, e):
    """F (1,) [N]: F_f sdot / sqrt(sdot^2 + v_eps^2)."""
    return e.friction_force * sdot / jnp.sqrt(sdot**2 + e.velocity_scale**2)


def potential(s, e):
    """V = 0: friction stores no energy."""
    return jnp.zeros((), dtype=s.dtype)


def power(s, sdot, e):
    """Dissipated power [W]: F sdot >= 0."""
    return jnp.sum(law(s, sdot, e) * sdot)


def params(specs, what) -> FrictionDamperParams:
    """Checks the descriptions (F_f >= 0, v_eps > 0, a non-zero axis) and makes their
    traced parameters."""
    axes = []
    for n, spec in enumerate(specs):
        label = element_label(what, spec, n)
        checked_scalar(spec.friction_force, f"{label}: friction_force")
        checked_scalar(spec.velocity_scale, f"{label}: velocity_scale", positive=True)
        axes.append(checked_axis(spec.axis_i, f"{label}: axis_i"))
    return FrictionDamperParams(
        **point_arrays(specs),
        axis_i=float64_array(axes),
        friction_force=float64_array([s.friction_force for s in specs]),
        velocity_scale=float64_array([s.velocity_scale for s in specs]),
    )
