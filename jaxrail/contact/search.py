"""The paper's contact search for one wheel, one wheelset and a whole vehicle.

Per wheel (docs/design.md §4): the rail section nearest the wheel profile origin (eqs. 3-5),
every strip of a fixed grid across each wheel surface against that locally straight
rail (:mod:`jaxrail.contact.strip`, vmapped), runs of penetrating strips as patches,
the deepest point of each patch refined below the strip spacing, and a wide patch
placed at the centre of its interpenetration (:mod:`jaxrail.contact.patches`). Results
come in fixed-size patch slots with a mask.

Every wheel surface gets ``max_patches`` slots; a wheel with several surfaces (the
paper's simplified profile: tread and flange) has each surface searched independently
and its slots in surface order.
"""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from ..compilation import traced_once
from ..profiles import Profile, WheelProfile
from ..track.rails import lateral_from_centre, rail_under_wheel, wheel_origin
from .patches import (SECANT_SPAN, find_patches, overlap_density, refine_maximum, secant_stencil,
                      stencil_curvature, wide_point)
from .strip import strip_point, wheel_frame

PARTS = ("y_deepest", "centre", "breadth")  # of a patch's contact point (search_wheel_parts)


class SearchConfig(eqx.Module):
    """Static settings of the search (changing them recompiles).

    Fields:
        strip_spacing: target distance between strips across a wheel surface [m];
            the strip count per surface is ``ceil(width / strip_spacing) + 1``.
        max_patches: patch slots per wheel surface. Not one for the simplified profile
            either: its tread keeps the S1002 hollow, whose two-point contact (tread and
            the tangent line near the V) needs two slots to hand over load continuously.
    """

    strip_spacing: float = eqx.field(static=True, default=1.0e-3)
    max_patches: int = eqx.field(static=True, default=3)

    def strip_grid(self, surface: Profile) -> Float[Array, " n"]:
        """Strip coordinates [m] across ``surface``, ends inset by 1e-6 m."""
        lo, hi = surface.domain
        count = math.ceil((hi - lo) / self.strip_spacing) + 1
        return jnp.linspace(lo + 1e-6, hi - 1e-6, count)

    def slots(self, wheel: WheelProfile) -> int:
        """Patch slots per wheel for this wheel profile."""
        return self.max_patches * len(wheel.surfaces)


class ContactPatches(eqx.Module):
    """Contact patches of one wheel (leading axes: ``(..., P)`` for P patch slots).

    Positions and vectors are global [m]; profile coordinates follow
    :mod:`jaxrail.profiles._base` (lateral toward the field side).

    Fields:
        active: slot holds a patch.
        penetration: refined largest depth of the patch into the rail [m], less the part
            shared with a neighbouring maximum of the same run (:func:`find_patches`), 0
            where inactive.
        surface: index of the wheel surface of the patch.
        y_wheel: u_w, wheel profile lateral coordinate of the contact point [m]: the
            deepest point of a narrow patch, the centre of the interpenetration of a
            wide one (:func:`jaxrail.contact.patches.overlap_centre`).
        s_wheel: s_w, angle on the wheel circle from its lowest point [rad] (eq. 12).
        dx: longitudinal offset of the contact point from the rail section [m] (eq. 13).
        y_rail: u_r, rail profile lateral coordinate [m] (eq. 15).
        s_rail: s_r, track arc length of the rail section [m] (eqs. 3-5).
        y_track: lateral position of the contact point from the design track centre
            [m], positive to the left, in the (canted) track plane (with the rail's
            irregularity).
        wheel_point, rail_point: the strip's wheel point and its foot on the rail [m].
        normal: unit contact normal, out of the rail into the wheel.
        frame: contact frame, columns [longitudinal t, lateral (normal x t), normal].
        contact_angle: angle of the normal from the rail's up axis [rad], positive
            when it tilts toward the track centre (flange contact ~ +70 deg).
        rolling_radius: wheel radius at ``y_wheel`` [m].
        curvature_wheel_x: wheel curvature in the rolling direction,
            ``cos(wheel profile angle) / rolling_radius`` [1/m].
        curvature_wheel_y, curvature_rail_y: lateral profile curvatures [1/m], convex
            toward the other body positive (the S1002 throat is negative).
        curvature_contact_y: relative lateral curvature of the patch [1/m] for Hertz
            (the sum of wheel and rail curvature where those are smooth): for a narrow
            patch the secant curvature of the gap over +-1 mm
            (:func:`jaxrail.contact.patches.secant_curvature`), continuous across the
            arc junctions of the UIC60 head; for a wide one the curvature a parabolic gap
            would need to overlap as widely (:func:`jaxrail.contact.patches.overlap_centre`),
            which stays positive and representative where the profiles conform.
    """

    active: Bool[Array, "... p"]
    penetration: Float[Array, "... p"]
    surface: Int[Array, "... p"]
    y_wheel: Float[Array, "... p"]
    s_wheel: Float[Array, "... p"]
    dx: Float[Array, "... p"]
    y_rail: Float[Array, "... p"]
    s_rail: Float[Array, "... p"]
    y_track: Float[Array, "... p"]
    wheel_point: Float[Array, "... p 3"]
    rail_point: Float[Array, "... p 3"]
    normal: Float[Array, "... p 3"]
    frame: Float[Array, "... p 3 3"]
    contact_angle: Float[Array, "... p"]
    rolling_radius: Float[Array, "... p"]
    curvature_wheel_x: Float[Array, "... p"]
    curvature_wheel_y: Float[Array, "... p"]
    curvature_rail_y: Float[Array, "... p"]
    curvature_contact_y: Float[Array, "... p"]


def _surface_strips(surface, wheel, rail, geometry, config):
    """The strip function of one wheel surface, its grid and all strips on it (whose
    rail feet carry no derivatives: the search differentiates only their depths)."""
    wheel_origin, frame, rail_origin, rail_axes, side = geometry

    def point(y, foot_derivatives=True):
        return strip_point(surface, wheel.nominal_radius, rail, y, wheel_origin, frame,
                           rail_origin, rail_axes, side, foot_derivatives)

    y_grid = config.strip_grid(surface)
    return point, y_grid, jax.vmap(lambda y: point(y, False))(y_grid)


def _surface_patches(surface, surface_index, wheel, rail, geometry, config, slots):
    """Patches of one wheel surface: strips, runs, refinement, contact data."""
    point, y_grid, strips = _surface_strips(surface, wheel, rail, geometry, config)
    index, active, keep, weights = find_patches(strips.depth, slots)
    depth_fn = lambda y: point(y, False).depth  # noqa: E731
    y_star = jax.vmap(lambda i: refine_maximum(depth_fn, y_grid, strips.depth, i, surface.domain))(index)
    centre, breadth, overlap = overlap_density(weights, strips.depth, y_grid, y_star)
    y_contact, blend = wide_point(y_star, centre, breadth)
    stretch = 1.0 + jax.vmap(surface.slope)(y_star) ** 2  # (arc length / wheel coordinate)^2
    stencil, span = jax.vmap(lambda y, k: secant_stencil(y, surface.domain, SECANT_SPAN / jnp.sqrt(k)))(
        y_star, stretch)
    # the refined depth and the secant's three in one evaluation of the strip function
    depths = jax.vmap(jax.vmap(depth_fn))(jnp.concatenate([y_star[:, None], stencil], axis=1))
    depth = keep * depths[:, 0]
    narrow = jax.vmap(stencil_curvature)(depths[:, 1:], span) / stretch
    _, _, rail_origin, rail_axes, side = geometry
    data = lambda *args: _contact_data(surface, surface_index, wheel, rail, point, *args,  # noqa: E731
                                       rail_origin, rail_axes, side)
    out = jax.vmap(data)(y_contact, active, depth, narrow + blend * (overlap - narrow))
    return dict(out, **dict(zip(PARTS, (y_star, centre, breadth))))


def _surface_deepest(surface, wheel, rail, geometry, config):
    """Refined signed depth [m] and coordinate [m] of the deepest strip of a surface
    (penetrating or not)."""
    point, y_grid, strips = _surface_strips(surface, wheel, rail, geometry, config)
    depth = jnp.where(strips.rail_inside > 0.5, strips.depth, -1.0e3)
    depth_fn = lambda y: point(y, False).depth  # noqa: E731
    # The deepest strip is chosen over the rail head only, but refined from the true
    # depths of its neighbours, as the search refines a patch: with a neighbour masked
    # to -1e3 m (its foot past the rail's end) the parabola puts the point half a
    # spacing on the far side, where the Newton steps after it are skipped (the depth
    # is not concave there). S1002 on UIC60 1:20 at +6.5 mm: the flange meets the gauge
    # corner at y_wheel = -38.70 mm, between the strips at -38.62 mm (0.081 mm deep) and
    # -39.62 mm (foot past the rail's end at -35.22 mm); the point went to -38.12 mm in
    # the flange root, and the quasi-static solve put it at the virtual penetration
    # with the flange 0.085 mm deep: roll 1.5e-3 rad and dr 2.2 mm off.
    y_star = refine_maximum(depth_fn, y_grid, strips.depth, jnp.argmax(depth),
                            surface.domain)
    return depth_fn(y_star), y_star


def contact_geometry(surface, rail, nominal_radius, y_wheel, y_rail, dx, rail_origin,
                     rail_axes, side):
    """Geometry of one contact point from its profile coordinates: the wheel at
    ``y_wheel`` [m] on ``surface``, the rail at ``y_rail`` [m], ``dx`` [m] along the
    rail tangent from the rail section (``rail_origin`` (3,), ``rail_axes`` (3, 3),
    global; ``side`` +1 left, -1 right). Returns a dict of the :class:`ContactPatches`
    fields ``rail_point``, ``normal``, ``frame``, ``contact_angle``, ``rolling_radius``
    and the curvatures but ``curvature_contact_y``."""
    t, n, b = rail_axes[:, 0], rail_axes[:, 1], rail_axes[:, 2]
    f, f1, f2 = rail.height_derivatives(y_rail)
    normal = (-side * f1 * n + b) / jnp.sqrt(1.0 + f1 * f1)
    w, w1, w2 = surface.height_derivatives(y_wheel)
    rolling_radius = nominal_radius + w
    return dict(
        rail_point=rail_origin + dx * t + side * y_rail * n + f * b,
        normal=normal,
        frame=jnp.stack([t, jnp.cross(normal, t), normal], axis=1),
        contact_angle=jnp.arctan(f1),
        rolling_radius=rolling_radius,
        curvature_wheel_x=1.0 / (jnp.sqrt(1.0 + w1 * w1) * rolling_radius),
        curvature_wheel_y=-w2 / (1.0 + w1 * w1) ** 1.5,
        curvature_rail_y=-f2 / (1.0 + f1 * f1) ** 1.5,
    )


def _contact_data(surface, surface_index, wheel, rail, point, y, active, depth, curvature,
                  rail_origin, rail_axes, side):
    """Contact data of the patch with contact point at wheel coordinate ``y``, penetration
    ``depth`` [m] and relative lateral curvature ``curvature`` [1/m]."""
    p = point(y)
    active = active & (depth > 0.0)
    return dict(
        active=active,
        penetration=jnp.where(active, depth, 0.0),
        surface=jnp.asarray(surface_index),
        y_wheel=y,
        s_wheel=p.s_wheel,
        dx=p.dx,
        y_rail=p.y_rail,
        wheel_point=p.wheel_point,
        curvature_contact_y=curvature,
        **contact_geometry(surface, rail, wheel.nominal_radius, y, p.y_rail, p.dx, rail_origin,
                           rail_axes, side),
    )


def _wheel_geometry(track, wheelset_position, wheelset_rotation, side, s_guess,
                    deflection=None):
    """Wheel origin, wheel frame and rail section of one wheel (eqs. 3-7), the rail
    from :mod:`jaxrail.track.rails`."""
    origin = wheel_origin(wheelset_position, wheelset_rotation, side)
    s_rail, rail_origin, rail_axes = rail_under_wheel(track, origin, side, s_guess, deflection)
    frame = wheel_frame(wheelset_rotation[:, 1], rail_axes[:, 0])
    return s_rail, (origin, frame, rail_origin, rail_axes, side)


def search_wheel(wheel: WheelProfile, track, wheelset_position, wheelset_rotation, side,
                 config: SearchConfig = SearchConfig(), s_guess=None,
                 deflection=None) -> ContactPatches:
    """Contact patches between one wheel and its rail.

    Arguments:
        wheel: the wheel profile (the same profile serves both sides).
        track: a :class:`jaxrail.track.Track`: its rails (:class:`jaxrail.track.Rails`,
            one profile for both, at their offset from the track centre) and its
            irregularity, if any (the wheel meets the rail where
            :mod:`jaxrail.track.rails` puts it).
        wheelset_position: wheelset centre, global, shape (3,) [m].
        wheelset_rotation: wheelset orientation, shape (3, 3), columns = body axes
            (forward, axle to the left, up) in global components.
        side: +1.0 left wheel, -1.0 right wheel (may be traced, e.g. vmapped).
        config: static search settings.
        s_guess: optional arc-length guess for the rail section [m].
        deflection: on a flexible track, this rail's (lateral, vertical) deflection
            (2,) [m] under the wheelset (:mod:`jaxrail.track.flexible`); None: rigid.

    Returns :class:`ContactPatches` with leading shape ``(P,)``.
    """
    return search_wheel_parts(wheel, track, wheelset_position, wheelset_rotation, side,
                              config, s_guess, deflection)[0]


def search_wheel_parts(wheel: WheelProfile, track, wheelset_position, wheelset_rotation, side,
                       config: SearchConfig = SearchConfig(), s_guess=None,
                       deflection=None) -> tuple[ContactPatches, dict]:
    """:func:`search_wheel` and the parts each patch's contact point is made of (:data:`PARTS`,
    each (P,) [m]): the refined deepest point, the centre of the interpenetration and its
    breadth, from which :func:`jaxrail.contact.patches.wide_point` places the point."""
    side = jnp.asarray(side, dtype=jnp.float64)
    rail = track.rails.profile
    s_rail, geometry = _wheel_geometry(track, wheelset_position, wheelset_rotation, side,
                                       s_guess, deflection)
    slots = config.slots(wheel)
    parts = [_surface_patches(s, k, wheel, rail, geometry, config, config.max_patches)
             for k, s in enumerate(wheel.surfaces)]
    data = {key: jnp.concatenate([part[key] for part in parts]) for key in parts[0]}
    located = {key: data.pop(key) for key in PARTS}
    data["surface"] = data["surface"].astype(jnp.int32)
    data["s_rail"] = jnp.full((slots,), s_rail)
    data["y_track"] = lateral_from_centre(track, s_rail, side, data["y_rail"], deflection)
    return ContactPatches(**data), located


@traced_once
def deepest_depth(wheel: WheelProfile, track, wheelset_position, wheelset_rotation, side,
                  config: SearchConfig = SearchConfig(), s_guess=None, deflection=None):
    """Largest signed depth [m] of a wheel into its rail over all strips and surfaces,
    refined below the strip spacing (negative: the wheel is clear of the rail by that
    normal distance). Used to put a wheelset on the rails (quasi-static geometry)."""
    side = jnp.asarray(side, dtype=jnp.float64)
    _, geometry = _wheel_geometry(track, wheelset_position, wheelset_rotation, side, s_guess,
                                  deflection)
    depths = [_surface_deepest(s, wheel, track.rails.profile, geometry, config)[0]
              for s in wheel.surfaces]
    return jnp.max(jnp.stack(depths))


@traced_once
def search_wheelset(wheel, track, wheelset_position, wheelset_rotation,
                    config: SearchConfig = SearchConfig(), s_guess=None,
                    deflection=None) -> ContactPatches:
    """Both wheels of a wheelset; leading shape ``(2, P)`` ordered (left, right).
    ``deflection``: on a flexible track, the rails' deflections (2, 2) [m] under this
    wheelset (left, right; lateral, vertical); None: rigid rails."""
    sides = jnp.array([1.0, -1.0])
    return jax.vmap(lambda side, d: search_wheel(wheel, track, wheelset_position,
                                                 wheelset_rotation, side, config, s_guess, d),
                    in_axes=(0, None if deflection is None else 0))(sides, deflection)


def search_vehicle(wheel, track, wheelset_positions, wheelset_rotations,
                   config: SearchConfig = SearchConfig(), s_guesses=None,
                   deflections=None) -> ContactPatches:
    """All wheels of a vehicle in one call: positions ``(W, 3)``, rotations ``(W, 3, 3)``,
    optional arc-length guesses ``(W,)`` and, on a flexible track, the rails'
    deflections ``(W, 2, 2)`` [m]; leading shape ``(W, 2, P)``."""
    return jax.vmap(
        lambda p, r, s, d: search_wheelset(wheel, track, p, r, config, s, d),
        in_axes=(0, 0, None if s_guesses is None else 0, None if deflections is None else 0),
    )(wheelset_positions, wheelset_rotations, s_guesses, deflections)
