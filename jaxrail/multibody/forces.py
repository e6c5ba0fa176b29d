"""Force elements: their kinds (:data:`FORCE_KINDS`) and their generalized forces.

The generalized force of a force or torque on a body (the Euler-parameter (pdot)
convention) is :mod:`.applied_forces`; its names ``point_force``, ``body_torque``,
``centre_loads`` and ``gravity_forces`` are importable from here as well.

Suspension elements (spring-dampers, bushings, bump stops) between body i and body j
(-1 for the ground) are written as a few deformation coordinates s(q_i, q_j) and a
law F(s, sdot) giving the generalised force -(ds/dq)^T F. The stiffness part is then
exactly minus the gradient of the element's potential, so conservative systems keep
their energy. The component of g_p along p (no work on the unit sphere) is removed,
so every g_p here is tangent.

Kinds and deformation coordinates (points and axes in the frames of their bodies):

    spring_damper (1): length L = |r_Pj - r_Pi|;  F = k (L - L0) + c Ldot.
    bushing (6):       u = B_i^T (r_Pj - r_Pi) and theta = vee(skew part of B_i^T B_j),
                       B = A frame (bushing axes in global); theta is the small-angle
                       rotation of frame j relative to frame i (sin of the angle about
                       one axis); F = K s + C sdot + F0 (six values each, diagonal).
    bump_stop (1):     s = a_i . (r_Pj - r_Pi), a_i = A_i axis_i; acts once s exceeds
                       the clearance: F = max(k (s - c) + d sdot, 0) for s > c, else 0.

Further kinds, each in a module of its own: ``table_spring`` (a nonlinear spring or
bump stop from a table, :mod:`.table_spring`), ``anti_roll_bar`` (:mod:`.anti_roll_bar`),
``friction_damper`` (:mod:`.friction_damper`), ``traction_rod`` (:mod:`.traction_rod`),
and two with internal states (``State.elements``), ``maxwell_damper`` and
``air_spring`` (:mod:`.elements_series`).
"""

import dataclasses
import typing
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..compilation import computed_once, traced_once
from . import quaternion as qt
from . import anti_roll_bar, friction_damper, table_spring, traction_rod
from ._values import (checked_axis, checked_vector, element_label, float64_array,
                      point_arrays)
from .element_geometry import line_length
from .elements_series import series_kinds
from .applied_forces import body_torque as body_torque
from .applied_forces import centre_loads as centre_loads
from .applied_forces import gravity_forces as gravity_forces
from .applied_forces import point_force as point_force
from .applied_forces import tangent
from .element_geometry import separation as _separation
from .joints import _check_frame, body_rows, body_sums, ground_extended


# ---- build-time descriptions --------------------------------------------------


@dataclasses.dataclass(frozen=True)
class SpringDamper:
    """Linear spring-damper between point_i of body i and point_j of body j.

    stiffness k [N/m], free_length L0 [m], damping c [N s/m]. Tension positive.
    """

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    stiffness: float
    free_length: float
    damping: float = 0.0
    name: str = ""
    kind: ClassVar[str] = "spring_damper"


@dataclasses.dataclass(frozen=True)
class Bushing:
    """Six-component linear bushing between body i and body j.

    The bushing frame is frame_i (columns = axes, in body i's frame) at point_i; on
    body j it is frame_j at point_j; at zero deflection both coincide. stiffness (6,):
    (kx, ky, kz [N/m], krx, kry, krz [N m/rad]); damping (6,) in [N s/m] and
    [N m s/rad]; preload (6,) [N, N m]: force the element carries at zero deflection,
    same sign as K s (positive pulls body j back towards -axis).
    """

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    stiffness: object
    damping: object = (0.0,) * 6
    frame_i: object = None
    frame_j: object = None
    preload: object = (0.0,) * 6
    name: str = ""
    kind: ClassVar[str] = "bushing"


@dataclasses.dataclass(frozen=True)
class BumpStop:
    """One-sided spring with clearance: pushes point_j back once it has moved more
    than `clearance` [m] beyond point_i along axis_i (body i frame, normalised).

    stiffness [N/m], damping [N s/m] (only while in contact; the force never pulls).
    """

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    axis_i: object
    clearance: float
    stiffness: float
    damping: float = 0.0
    name: str = ""
    kind: ClassVar[str] = "bump_stop"


# ---- traced parameters ------------------------------------------------------------


class SpringDamperParams(eqx.Module):
    """(k, 3) points [m]; (k,) stiffness [N/m], damping [N s/m], free_length [m]."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    stiffness: Float[Array, " k"]
    damping: Float[Array, " k"]
    free_length: Float[Array, " k"]


class BushingParams(eqx.Module):
    """(k, 3) points [m]; (k, 3, 3) frames; (k, 6) stiffness, damping, preload."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    frame_i: Float[Array, "k 3 3"]
    frame_j: Float[Array, "k 3 3"]
    stiffness: Float[Array, "k 6"]
    damping: Float[Array, "k 6"]
    preload: Float[Array, "k 6"]


class BumpStopParams(eqx.Module):
    """(k, 3) points [m] and axis; (k,) clearance [m], stiffness, damping."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    axis_i: Float[Array, "k 3"]
    clearance: Float[Array, " k"]
    stiffness: Float[Array, " k"]
    damping: Float[Array, " k"]


# ---- one element: deformation coordinates, law, potential ---------------------


def _spring_coords(qi, qj, e):
    return line_length(qi, qj, e)


def _spring_law(s, sdot, e):
    return e.stiffness * (s - e.free_length) + e.damping * sdot


def _spring_potential(s, e):
    return 0.5 * e.stiffness * jnp.sum((s - e.free_length) ** 2)


def _bushing_coords(qi, qj, e):
    # u = B_i^T d; theta = vee(skew part of C), C = B_i^T B_j:
    # theta = (C_zy - C_yz, C_xz - C_zx, C_yx - C_xy) / 2.
    a_i, a_j, d = _separation(qi, qj, e)
    b_i, b_j = qt.matmul(a_i, e.frame_i), qt.matmul(a_j, e.frame_j)
    u = jnp.sum(b_i * d[:, None], axis=0)
    c = jnp.sum(b_i[:, :, None] * b_j[:, None, :], axis=0)
    theta = 0.5 * jnp.stack([c[2, 1] - c[1, 2], c[0, 2] - c[2, 0], c[1, 0] - c[0, 1]])
    return jnp.concatenate([u, theta])


def _bushing_law(s, sdot, e):
    return computed_once(e.stiffness * s + e.damping * sdot + e.preload)


def _bushing_potential(s, e):
    return jnp.sum(0.5 * e.stiffness * s**2 + e.preload * s)


def _bump_coords(qi, qj, e):
    a_i, _, d = _separation(qi, qj, e)
    axis = qt.matvec(a_i, e.axis_i / jnp.sqrt(qt.dot(e.axis_i, e.axis_i)))
    return qt.dot(axis, d)[None]


def _bump_law(s, sdot, e):
    gap = s - e.clearance
    push = jnp.maximum(e.stiffness * gap + e.damping * sdot, 0.0)
    return jnp.where(gap > 0.0, push, 0.0)


def _bump_potential(s, e):
    return 0.5 * e.stiffness * jnp.sum(jnp.maximum(s - e.clearance, 0.0) ** 2)


def _spring_params(specs, what):
    return SpringDamperParams(
        **point_arrays(specs),
        stiffness=float64_array([s.stiffness for s in specs]),
        damping=float64_array([s.damping for s in specs]),
        free_length=float64_array([s.free_length for s in specs]),
    )


def _bushing_params(specs, what):
    def frame(f, side):
        return np.eye(3) if f is None else _check_frame(f, f"{what} {side}")

    def six(values, name):
        return float64_array([checked_vector(v, (6,), f"{what} {name}") for v in values])

    return BushingParams(
        **point_arrays(specs),
        frame_i=float64_array([frame(s.frame_i, "frame_i") for s in specs]),
        frame_j=float64_array([frame(s.frame_j, "frame_j") for s in specs]),
        stiffness=six([s.stiffness for s in specs], "stiffness"),
        damping=six([s.damping for s in specs], "damping"),
        preload=six([s.preload for s in specs], "preload"),
    )


def _bump_params(specs, what):
    axes = [checked_axis(s.axis_i, f"{element_label(what, s, n)} axis_i")
            for n, s in enumerate(specs)]
    return BumpStopParams(
        **point_arrays(specs),
        axis_i=float64_array(axes),
        clearance=float64_array([s.clearance for s in specs]),
        stiffness=float64_array([s.stiffness for s in specs]),
        damping=float64_array([s.damping for s in specs]),
    )


class ForceKind(typing.NamedTuple):
    """One kind of force element.

    Fields:
        coordinates: ``s(q_i, q_j, e)``, the deformation coordinates (c,).
        law: ``F(s, sdot, e)`` (c,), the generalized force along s (tension positive:
            the bodies feel ``-(ds/dq)^T F``); for a kind with internal states,
            ``F(s, sdot, e, z)``.
        potential: ``V(s, e)`` [J], the stored energy (0 for a kind that stores none);
            for a kind with internal states, ``V(s, e, z)``.
        params: ``params(specs, what)`` checks the kind's build-time descriptions and
            makes its traced parameters (leading axis: the elements).
        power: ``P(s, sdot, e)`` [W] (``P(s, sdot, e, z)`` with internal states), the
            power the element dissipates (>= 0), or None where it dissipates none.
        states: the number of internal states per element (0: none).
        rate: ``zdot(s, sdot, e, z)`` (states,), the internal states' derivatives, for
            a kind with internal states.
        initial: ``z0(s, e)`` (states,), the internal states at rest with deformation
            s (the element unloaded by its internal states), for such a kind.
    """

    coordinates: typing.Callable
    law: typing.Callable
    potential: typing.Callable
    params: typing.Callable
    power: typing.Callable | None = None
    states: int = 0
    rate: typing.Callable | None = None
    initial: typing.Callable | None = None


def _spring_power(s, sdot, e):
    return jnp.sum(e.damping * sdot**2)


def _bushing_power(s, sdot, e):
    return jnp.sum(e.damping * sdot**2)


def _bump_power(s, sdot, e):
    gap = s - e.clearance
    push = e.stiffness * gap + e.damping * sdot
    return jnp.sum(jnp.where((gap > 0.0) & (push > 0.0), e.damping * sdot**2, 0.0))


FORCE_KINDS = {
    "spring_damper": ForceKind(_spring_coords, _spring_law, _spring_potential, _spring_params,
                               _spring_power),
    "bushing": ForceKind(_bushing_coords, _bushing_law, _bushing_potential, _bushing_params,
                         _bushing_power),
    "bump_stop": ForceKind(_bump_coords, _bump_law, _bump_potential, _bump_params,
                           _bump_power),
    **series_kinds(ForceKind),
    "table_spring": ForceKind(_bump_coords, table_spring.law, table_spring.potential,
                              table_spring.params, table_spring.power),
    "anti_roll_bar": ForceKind(anti_roll_bar.coordinates, anti_roll_bar.law,
                               anti_roll_bar.potential, anti_roll_bar.params,
                               anti_roll_bar.power),
    "friction_damper": ForceKind(_bump_coords, friction_damper.law, friction_damper.potential,
                                 friction_damper.params, friction_damper.power),
    "traction_rod": ForceKind(_spring_coords, _spring_law, _spring_potential,
                              traction_rod.params, _spring_power),
}


def element_deformation(kind: str, qi, qj, e) -> Array:
    """Deformation coordinates s of one element of `kind` (see module docstring)."""
    return FORCE_KINDS[kind].coordinates(qi, qj, e)


def _law_and_rate(kind, s, sdot, e, z):
    """(F, zdot) of one element at deformation s, rate sdot and internal states z
    (zdot None for a kind without internal states)."""
    k = FORCE_KINDS[kind]
    if k.states == 0:
        return k.law(s, sdot, e), None
    return k.law(s, sdot, e, z), k.rate(s, sdot, e, z)


def _one_element(kind, qi, qj, vi, vj, e, z=None):
    """(g_i (7,), g_j (7,), zdot) of one element: -(ds/dq)^T F(s, sdot[, z]), sdot and
    the transpose product by forward and reverse AD of s(q_i, q_j)."""
    coords = FORCE_KINDS[kind].coordinates

    def s_of(qi, qj):
        return coords(qi, qj, e)

    s, pullback = jax.vjp(s_of, qi, qj)
    sdot = jax.jvp(s_of, (qi, qj), (vi, vj))[1]
    force, zdot = _law_and_rate(kind, s, sdot, e, z)
    gi, gj = pullback(-force)
    gi = jnp.concatenate([gi[:3], tangent(qi[3:], gi[3:])])
    gj = jnp.concatenate([gj[:3], tangent(qj[3:], gj[3:])])
    return gi, gj, zdot


def _pairs(body_i, body_j, x_ext):
    """The rows (k, 7) of x_ext (n + 1, 7) (row n: the ground's) of the elements'
    bodies i and j."""
    return body_rows(body_i, x_ext), body_rows(body_j, x_ext)


def _coordinate_pairs(body_i, body_j, q):
    """The coordinates (k, 7) of the elements' bodies i and j (the ground at rest at the
    origin) from q (7 n,)."""
    return _pairs(body_i, body_j, ground_extended(q.reshape(-1, 7)))


def _velocity_pairs(body_i, body_j, qdot):
    """The velocities (k, 7) of the elements' bodies i and j (the ground's zero)."""
    v = qdot.reshape(-1, 7)
    return _pairs(body_i, body_j, jnp.concatenate([v, jnp.zeros((1, 7), dtype=v.dtype)]))


@traced_once
def element_loads(kind: str, body_i, body_j, e, q, qdot, z=None):
    """(g (7 n,), zdot (k, r) or None): the summed generalized forces of the k elements
    of one kind and the rates of their internal states.

    body_i, body_j: static int sequences (k,), -1 for ground; e: the kind's params
    with leading axis k; q, qdot (7 n,); z (k, r): the internal states of a kind that
    has r of them (None otherwise).
    """
    n = q.shape[0] // 7
    q_i, q_j = _coordinate_pairs(body_i, body_j, q)
    v_i, v_j = _velocity_pairs(body_i, body_j, qdot)
    if FORCE_KINDS[kind].states == 0:
        gi, gj, _ = jax.vmap(lambda a, b, c, d, p: _one_element(kind, a, b, c, d, p))(
            q_i, q_j, v_i, v_j, e)
        zdot = None
    else:
        gi, gj, zdot = jax.vmap(lambda a, b, c, d, p, w: _one_element(kind, a, b, c, d, p, w))(
            q_i, q_j, v_i, v_j, e, z)
    return (body_sums(body_i, gi, n) + body_sums(body_j, gj, n)).reshape(-1), zdot


def element_forces(kind: str, body_i, body_j, e, q, qdot, z=None) -> Float[Array, " 7n"]:
    """Summed generalized forces (7 n,) of the k elements of one kind
    (:func:`element_loads`)."""
    return element_loads(kind, body_i, body_j, e, q, qdot, z)[0]


def element_potential(kind: str, body_i, body_j, e, q, z=None) -> Float[Array, ""]:
    """Summed stored energy [J] of the k elements of one kind (dampers excluded);
    z (k, r): the internal states of a kind that has them."""
    coords, potential = FORCE_KINDS[kind].coordinates, FORCE_KINDS[kind].potential
    q_i, q_j = _coordinate_pairs(body_i, body_j, q)
    if FORCE_KINDS[kind].states == 0:
        v = jax.vmap(lambda a, b, p: potential(coords(a, b, p), p))(q_i, q_j, e)
    else:
        v = jax.vmap(lambda a, b, p, w: potential(coords(a, b, p), p, w))(q_i, q_j, e, z)
    return jnp.sum(v)


def element_initial_states(kind: str, body_i, body_j, e, q) -> Float[Array, "k r"]:
    """The internal states (k, r) of the elements of a kind that has them, at rest at q
    (7 n,): each element unloaded through its internal states (``ForceKind.initial``)."""
    coords, initial = FORCE_KINDS[kind].coordinates, FORCE_KINDS[kind].initial
    q_i, q_j = _coordinate_pairs(body_i, body_j, q)
    return jax.vmap(lambda a, b, p: initial(coords(a, b, p), p))(q_i, q_j, e)


def element_power(kind: str, body_i, body_j, e, q, qdot, z=None) -> Float[Array, ""]:
    """Summed power [W] the k elements of one kind dissipate (0 for a kind that
    dissipates none); z (k, r): the internal states of a kind that has them."""
    k = FORCE_KINDS[kind]
    if k.power is None:
        return jnp.zeros((), dtype=q.dtype)
    q_i, q_j = _coordinate_pairs(body_i, body_j, q)
    v_i, v_j = _velocity_pairs(body_i, body_j, qdot)

    def one(a, b, c, d, p, *w):
        s, sdot = jax.jvp(lambda x, y: k.coordinates(x, y, p), (a, b), (c, d))
        return k.power(s, sdot, p, *w)
    extra = () if k.states == 0 else (z,)
    return jnp.sum(jax.vmap(one)(q_i, q_j, v_i, v_j, e, *extra))
