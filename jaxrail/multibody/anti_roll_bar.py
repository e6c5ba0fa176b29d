"""The anti-roll bar: a torsion bar between two bodies that resists only their
relative roll.

Layout (body frames x forward, y left, z up, as in `jaxrail.vehicles`): the bar lies
across body i, along its y axis, centred at point_i; an arm of length l_a at each end
points along x; a vertical drop link at y = +b (left) and y = -b (right) joins each
arm's end to body j, whose link points are point_j +- b y_j. The deformation coordinate
is the relative roll of body j against body i,

    theta = (dz_left - dz_right) / (2 b),

dz the vertical displacements (along z_i, body i's frame) of body j's link points
relative to body i's. The link points' offsets cancel: dz_left - dz_right =
2 b z_i . (A_j e_y) exactly, so theta = z_i . y_j (the sine of the relative roll for a
roll alone), whatever point_i and point_j are; it is computed in that form. Bounce
(both links alike), lateral motion, yaw and pitch of one body against the other leave
theta = 0 and the bar unloaded.

Roll stiffness (links vertical, arms and links rigid, small angles): a relative roll
theta raises the left link by b theta and lowers the right one by b theta; each turns
its arm, so the two ends of the bar turn by +b theta / l_a and -b theta / l_a, and the
bar twists by phi = 2 b theta / l_a. It stores

    V = k_t phi^2 / 2 = K_roll theta^2 / 2,   K_roll = k_t (2 b / l_a)^2,

and its torque k_t phi pushes each link with k_t phi / l_a, opposite at the two sides,
a couple of 2 b k_t phi / l_a = K_roll theta on each body: the moment M = K_roll theta
(+ c theta_dot with the optional damping c [N m s/rad]) is dV/dtheta. A long arm makes
a soft bar, a wide link spacing a stiff one. The links' and bushings' compliance would
add in series; give it through a smaller k_t.
"""

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from . import quaternion as qt
from ._values import checked_scalar, element_label, float64_array, point_arrays


@dataclasses.dataclass(frozen=True)
class AntiRollBar:
    """Anti-roll bar between body i (carrying the bar) and body j (module docstring).

    point_i, point_j (3,) [m]: the bar's centre on body i and the point midway between
    the links' ends on body j (body frames; they mark the bar and do not enter its
    force, a pure couple). torsional_stiffness k_t [N m/rad] of the bar, arm_length
    l_a [m] > 0, half_spacing b [m] > 0 of the drop links; damping [N m s/rad] in roll.
    """

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    torsional_stiffness: float
    arm_length: float
    half_spacing: float
    damping: float = 0.0
    name: str = ""
    kind: ClassVar[str] = "anti_roll_bar"


class AntiRollBarParams(eqx.Module):
    """(k, 3) points [m]; (k,) torsional_stiffness [N m/rad], arm_length [m],
    half_spacing [m], damping [N m s/rad]."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    torsional_stiffness: Float[Array, " k"]
    arm_length: Float[Array, " k"]
    half_spacing: Float[Array, " k"]
    damping: Float[Array, " k"]


def roll_stiffness(e) -> Array:
    """K_roll = k_t (2 b / l_a)^2 [N m/rad] of the bar(s) ``e``."""
    return e.torsional_stiffness * (2.0 * e.half_spacing / e.arm_length) ** 2


def coordinates(qi, qj, e):
    """theta (1,): z_i . y_j, the relative roll of body j against body i."""
    z_i = qt.rotation_matrix(qi[3:])[:, 2]
    y_j = qt.rotation_matrix(qj[3:])[:, 1]
    return qt.dot(z_i, y_j)[None]


def law(s, sdot, e):
    """M (1,) [N m]: K_roll theta + c theta_dot."""
    return roll_stiffness(e) * s + e.damping * sdot


def potential(s, e):
    """V [J]: K_roll theta^2 / 2."""
    return 0.5 * roll_stiffness(e) * jnp.sum(s**2)


def power(s, sdot, e):
    """Dissipated power [W]: c theta_dot^2."""
    return jnp.sum(e.damping * sdot**2)


def params(specs, what) -> AntiRollBarParams:
    """Checks the descriptions (k_t, c >= 0; l_a, b > 0) and makes their parameters."""
    for n, spec in enumerate(specs):
        label = element_label(what, spec, n)
        for field, positive in (("torsional_stiffness", False), ("arm_length", True),
                                ("half_spacing", True), ("damping", False)):
            checked_scalar(getattr(spec, field), f"{label}: {field}", positive)
    return AntiRollBarParams(
        **point_arrays(specs),
        torsional_stiffness=float64_array([s.torsional_stiffness for s in specs]),
        arm_length=float64_array([s.arm_length for s in specs]),
        half_spacing=float64_array([s.half_spacing for s in specs]),
        damping=float64_array([s.damping for s in specs]),
    )
