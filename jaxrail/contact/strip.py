"""One wheel strip against a locally straight rail: eqs. (6)-(16) of the paper.

A *strip* is the circle of the wheel at lateral profile coordinate ``y`` (field side
positive, from the taping line). The rail section ``s_r`` has been found (eqs. 3-5) and
the rail is straight around it, so the rail surface is the sweep of its profile along
the rail tangent ``t``. For a strip this module computes, in closed form:

- ``s_w``, the angle on the strip circle where the wheel surface normal lies in the
  rail's cross-section plane (eq. 12, with the slope ``F'`` the OCR lost):
  ``sin s_w = side * F'(y) * tan(alpha)``, ``sin(alpha) = axle . t``;
- the wheel point ``P`` and its longitudinal offset from the rail section
  ``dx = side * (y + R(y) F'(y)) * sin(alpha)`` (eq. 13, corrected);
- the rail lateral coordinate ``u_r`` whose rail normal passes through ``P`` (eq. 15),
  by a fixed number of safeguarded Newton steps (the rail head is convex);
- the signed depth of ``P`` below the rail surface along the rail normal (eq. 16:
  positive = penetration).

Frames: ``t, n, b`` are the rail frame columns (global, unit): along the track, lateral
to the left, up. ``side`` is +1 for the left wheel/rail and -1 for the right one; profile
lateral coordinates point to the field side, i.e. along ``side * n`` (rail) and
``side * axle`` (wheel). The wheel angle ``s_w`` is measured on the strip circle from
its lowest point (``-b_w``) toward the wheel frame's forward axis ``n_w``.
"""

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.custom_derivatives import SymbolicZero
from jaxtyping import Array, Float

from ..profiles import Profile, below_tangent, frozen

RAIL_NEWTON_STEPS = 5


class WheelFrame(NamedTuple):
    """Wheel frame of eq. (7) for one wheel (global components, unit vectors)."""

    axle: Float[Array, "3"]  # a_w: wheelset axle, pointing left
    up: Float[Array, "3"]  # b_w = t x a / |t x a|
    forward: Float[Array, "3"]  # n_w = a x b_w
    sin_alpha: Float[Array, ""]  # a . t: yaw of the axle relative to the rail section
    cos_alpha: Float[Array, ""]


class StripPoint(NamedTuple):
    """Geometry of one strip against the rail (scalars unless noted)."""

    depth: Float[Array, ""]  # signed depth along the rail normal [m], > 0 penetrating
    s_wheel: Float[Array, ""]  # s_w [rad]
    dx: Float[Array, ""]  # longitudinal offset along t from the rail section [m]
    y_rail: Float[Array, ""]  # u_r: rail profile coordinate of the foot point [m]
    wheel_point: Float[Array, "3"]  # P, global [m]
    rail_inside: Float[Array, ""]  # 1.0 where the foot point is inside the rail domain


def wheel_frame(axle: Float[Array, "3"], t: Float[Array, "3"]) -> WheelFrame:
    """Eq. (7): a frame that shares the axle and is aligned with the rail tangent."""
    up = jnp.cross(t, axle)
    cos_alpha = jnp.linalg.norm(up)
    up = up / cos_alpha
    return WheelFrame(axle, up, jnp.cross(axle, up), axle @ t, cos_alpha)


def strip_angle(slope: Float[Array, ""], frame: WheelFrame, side) -> Float[Array, ""]:
    """Eq. (12) corrected: ``s_w = arcsin(side * F'(y) * tan(alpha))`` [rad]."""
    arg = side * slope * frame.sin_alpha / frame.cos_alpha
    return jnp.arcsin(jnp.clip(arg, -0.999, 0.999))


def longitudinal_offset(y, radius, slope, frame: WheelFrame, side) -> Float[Array, ""]:
    """Eq. (13) corrected: ``dx = side * (y + R F') * sin(alpha)`` [m].

    Closed form of ``(P - rail_origin) . t`` once the wheel profile origin lies in the
    rail section plane (eq. 5); kept for documentation and tests."""
    return side * (y + radius * slope) * frame.sin_alpha


def _foot_newton(rail: Profile, eta, zeta, u):
    """One safeguarded Newton step of eq. (15) from ``u`` [m], clipped to the rail
    domain, and the foot residual ``g(u)`` [m] it started from (:func:`rail_foot`)."""
    lo, hi = rail.domain
    f, f1, f2 = rail.height_derivatives(u)
    g = (eta - u) + (zeta - f) * f1
    dg = -1.0 - f1 * f1 + (zeta - f) * f2
    # On a convex head dg <= -1 near the foot; the floor guards far-away points.
    dg = jnp.minimum(dg, -0.5)
    return jnp.clip(u - g / dg, lo, hi), g


def rail_foot(rail: Profile, eta, zeta, derivatives: bool = True
              ) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Eq. (15): the rail coordinate ``u`` whose normal passes through ``(eta, zeta)``.

    ``(eta, zeta)`` are the point's field-side-lateral and vertical coordinates in the
    rail section plane [m]. The profile's closed form where it has one
    (:meth:`jaxrail.profiles.Profile.normal_foot`: the UIC60 head's arcs and flanks), else
    Newton on ``g(u) = (eta - u) + (zeta - f(u)) f'(u)`` from the vertical projection,
    clipped to the rail domain; unique on a convex head. Returns
    ``(u, valid)`` with ``valid = 1.0`` when the point lies over the rail head
    (``eta`` inside the domain), ``u`` did not hit the domain ends and the Newton
    residual converged (below 1e-9 m); elsewhere the depth has no meaning (a strip
    beside the rail, e.g. the back of the flange, is never in contact).

    The closed form and the steps carry no derivatives; ``u``'s are the implicit
    function theorem's (:func:`_foot`), first and second derivatives exact. ``derivatives=False``
    (static): ``u`` without derivatives, for a caller that differentiates only the
    depth (:func:`depth_at_foot`).
    """
    lo, hi = rail.domain
    fixed = frozen((rail, eta, zeta))
    u = fixed[0].normal_foot(*fixed[1:])
    if u is None:  # the last step is _foot's where u carries derivatives
        u, _ = jax.lax.scan(lambda u, _: (_foot_newton(*fixed, u)[0], None),
                            jnp.clip(fixed[1], lo, hi), None,
                            length=RAIL_NEWTON_STEPS - (1 if derivatives else 0))
    u = _foot(rail, eta, zeta, u) if derivatives else u  # the search's u has no derivatives
    converged = jnp.abs(_foot_newton(*fixed, jax.lax.stop_gradient(u))[1]) < 1e-9
    valid = (eta > lo) & (eta < hi) & (u > lo) & (u < hi) & converged
    return u, jnp.where(valid, 1.0, 0.0)


def _is_zero(tangent) -> bool:
    return isinstance(tangent, SymbolicZero)


def _dense(tangent):
    """``tangent`` (a pytree) with its symbolic zero leaves as arrays of zeros."""
    return jax.tree.map(lambda t: np.zeros(t.shape, t.dtype) if _is_zero(t) else t, tangent,
                        is_leaf=_is_zero)


def _at_the_foot(function):
    """A custom-JVP function ``f(rail, eta, zeta, u)`` of the converged rail foot ``u``
    (:func:`rail_foot`; its own tangent ignored) whose tangent is
    ``function(rail, eta, zeta, v)``'s in ``(rail, eta, zeta)`` at a fixed ``v``:
    ``v = u`` in value, but one Newton step from ``u`` in the inputs, so that the
    rule, differentiated again, follows the foot and second derivatives are exact.
    Its value is ``function(rail, eta, zeta, u)``. Inputs without a tangent (a profile
    held fixed) take no tangent computation."""
    wrapped = jax.custom_jvp(function)

    def rule(primals, tangents):
        rail, eta, zeta, u = primals
        value = function(rail, eta, zeta, u)
        live = [k for k in range(3)
                if not all(map(_is_zero, jax.tree.leaves(tangents[k], is_leaf=_is_zero)))]
        if not live:
            return value, jnp.zeros_like(value)
        moving = _foot_newton(rail, eta, zeta, jax.lax.stop_gradient(u))[0]

        def at_moving(*moved):
            inputs = list(primals[:3])
            for k, x in zip(live, moved):
                inputs[k] = x
            return function(*inputs, moving)

        return value, jax.jvp(at_moving, tuple(primals[k] for k in live),
                              tuple(_dense(tangents[k]) for k in live))[1]

    wrapped.defjvp(rule, symbolic_zeros=True)
    return wrapped


_foot = _at_the_foot(lambda rail, eta, zeta, u: _foot_newton(rail, eta, zeta, u)[0])
"""``u`` [m] itself (the value of one more Newton step from the converged foot) with
the implicit function theorem's derivatives, -g_theta / g_u."""


def signed_depth(rail: Profile, u, eta, zeta) -> Float[Array, ""]:
    """Distance of ``(eta, zeta)`` below the rail surface along the rail normal at ``u``
    [m] (eq. 16; positive = inside the rail).

    It is the distance to the rail's tangent line at ``u``, whose derivative in ``u`` is
    ``-f'' g(u) / (1 + f'^2)^(3/2)`` with ``g`` the foot residual of :func:`rail_foot`:
    zero at the foot, so the depth's first derivatives need none of ``u``
    (:func:`depth_at_foot`)."""
    f, f1, _ = rail.height_derivatives(u)
    return below_tangent(eta, zeta, u, f, f1)


def _depth_at(rail, eta, zeta, u):
    return signed_depth(rail, u, eta, zeta)


depth_at_foot = _at_the_foot(_depth_at)
"""``depth_at_foot(rail, eta, zeta, u)``: :func:`signed_depth` [m] at the rail foot
``u`` [m] of ``(eta, zeta)`` (:func:`rail_foot`), for a caller that differentiates the
depth but not the foot. Its first derivative is that of the distance to the tangent
line at a fixed ``u`` (stationary in ``u`` at the foot), which costs none of the foot's
tangents; its second derivatives follow the foot (:func:`_at_the_foot`)."""


def wheel_surface_point(surface: Profile, nominal_radius, y, wheel_origin: Float[Array, "3"],
                        frame: WheelFrame, side):
    """The point of the strip at wheel profile coordinate ``y`` [m] that the search
    tests against the rail (the strip's lowest point toward the rail, at the angle
    ``s_w`` of eq. 12), global [m], and ``s_w`` [rad]. Arguments as :func:`strip_point`."""
    height, slope, _ = surface.height_derivatives(y)
    radius = nominal_radius + height
    # sin and cos of s_w (eq. 12, as in strip_angle) without trigonometric functions;
    # s_w itself is computed only where a caller uses it.
    sin_w = jnp.clip(side * slope * frame.sin_alpha / frame.cos_alpha, -0.999, 0.999)
    radial = -jnp.sqrt(1.0 - sin_w * sin_w) * frame.up + sin_w * frame.forward
    return wheel_origin + side * y * frame.axle + radius * radial, jnp.arcsin(sin_w)


def strip_point(
    surface: Profile,
    nominal_radius,
    rail: Profile,
    y,
    wheel_origin: Float[Array, "3"],
    frame: WheelFrame,
    rail_origin: Float[Array, "3"],
    rail_axes: Float[Array, "3 3"],
    side,
    foot_derivatives: bool = True,
) -> StripPoint:
    """Geometry of the strip at wheel profile coordinate ``y`` [m].

    Arguments:
        surface, nominal_radius: the wheel surface and rolling radius at the taping
            line [m] (rolling radius ``R(y) = nominal_radius + height(y)``).
        rail: the rail profile.
        y: wheel lateral profile coordinate [m], field side positive.
        wheel_origin: the wheel profile origin (taping line on the axle), global [m].
        frame: :func:`wheel_frame` of this wheel.
        rail_origin, rail_axes: rail profile origin [m] and rail frame ``[t n b]``
            (columns, global) at the rail section ``s_r``.
        side: +1.0 left wheel, -1.0 right wheel.
        foot_derivatives: False (static) where only the depth is differentiated: the
            rail foot ``u_r`` then carries no derivatives and the depth is the
            rail's :meth:`~jaxrail.profiles.Profile.normal_foot_depth` where it has
            one, else :func:`depth_at_foot`'s.
    """
    point, s_w = wheel_surface_point(surface, nominal_radius, y, wheel_origin, frame, side)
    rel = point - rail_origin
    t, n, b = rail_axes[:, 0], rail_axes[:, 1], rail_axes[:, 2]
    eta, zeta = side * (rel @ n), rel @ b
    u, inside = rail_foot(rail, eta, zeta, foot_derivatives)
    if foot_derivatives:
        depth = signed_depth(rail, u, eta, zeta)
    else:  # the rail's closed form where it has one (the UIC60 head), else from the foot
        depth = rail.normal_foot_depth(eta, zeta)
        if depth is None:
            depth = depth_at_foot(rail, eta, zeta, u)
    return StripPoint(depth, s_w, rel @ t, u, point, inside)
