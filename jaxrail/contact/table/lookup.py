"""Looking a wheel's contact up in a table: its pose relative to its rail, the spline
block around it, the two approach levels around its height, and the contact patches
derived from the interpolated parts as the search derives them."""

import jax
import jax.numpy as jnp
import numpy as np

from ...compilation import computed_once, traced_once
from ...compilation.windows import window_map
from ...track.rails import lateral_from_centre, rail_under_wheel, wheel_origin
from ..patches import wide_point
from ..search import ContactPatches, contact_geometry
from ..strip import wheel_frame, wheel_surface_point
from .grid import _RATES, _VALUES, FIELDS, ContactTable
from .spline import _pose_weights


def relative_pose(track, radius, wheelset_position, wheelset_rotation, side, deflection=None):
    """Pose of one wheel relative to its rail (module docstring), the rail moved by
    ``deflection`` (2,) [m] on a flexible track (:func:`jaxrail.track.rail_under_wheel`).

    Returns ``(lateral, vertical, yaw, roll, s_rail, rail_origin, rail_axes, wheel_origin,
    frame)``: the four pose coordinates [m, m, rad, rad], the rail section's arc length
    [m], origin (3,) and axes (3, 3), and the wheel's origin (3,) and
    :class:`~jaxrail.contact.strip.WheelFrame`."""
    axle = wheelset_rotation[:, 1]
    origin = wheel_origin(wheelset_position, wheelset_rotation, side)
    s_rail, rail_origin, rail_axes = rail_under_wheel(track, origin, side,
                                                      deflection=deflection)
    frame = wheel_frame(axle, rail_axes[:, 0])
    taping = origin - radius * frame.up - rail_origin
    local = rail_axes.T @ axle
    roll = jnp.arcsin(jnp.clip(local[2], -1.0, 1.0))
    yaw = jnp.arctan2(-local[0], local[1])
    return (taping @ rail_axes[:, 1], taping @ rail_axes[:, 2], yaw, roll, s_rail, rail_origin,
            rail_axes, origin, frame)


def _weighted_nodes(window, weight):
    """(A,): the heights' window (1, *block, A) summed over the block's nodes with
    their weights (N,)."""
    return weight @ window.reshape(-1, window.shape[-1])


def _weighted_levels(window, weight):
    """(2, slots x fields): the coefficients' window (1, 2, *block, slots x fields), the
    block at two approach levels, summed over the nodes with their weights (N,) level
    by level: a matrix-vector product per level that reads the window as stored (no
    transpose)."""
    block = window.reshape(2, weight.shape[0], -1)
    return jnp.einsum("ln,lnf->lf", jnp.broadcast_to(weight, (2, weight.shape[0])), block)


def _two_levels(heights, vertical):
    """The levels ``i, i + 1`` around the wheel's ``vertical`` position [m] (``heights``
    (A,) decreasing: the wheel lower at deeper levels; the first or last pair beyond
    them)."""
    i = jnp.clip(jnp.sum(heights > vertical, dtype=jnp.int32) - 1, 0, heights.shape[0] - 2)
    return i + jnp.arange(2, dtype=jnp.int32)


def _along_levels(heights, fields, vertical, levels):
    """Per slot the depth [m] and the geometry (:data:`GEOMETRY`) at the wheel's
    ``vertical`` position [m] from the two approach levels around it (``heights`` (2,),
    the wheel lower at the second; ``fields`` (2, P, F); their depths ``levels`` (2,)),
    by cubic Hermite interpolation in the vertical position (C1): the depth from each
    level's depth and slope (beyond the levels, the nearer level's line), the geometry
    (a tuple, (P,) per field) from its values and rates (beyond the levels, the nearer
    level's values)."""
    z0, z1 = heights[0], heights[1]
    span = z0 - z1  # the wheel comes down by this from level i to i + 1
    t = jnp.clip((z0 - vertical) / span, 0.0, 1.0)
    # No patch is deeper than the level's deepest depth, and none deepens faster than
    # the wheel comes down (guards against nodes where the search's refined depth jumps)
    slope = jnp.clip(fields[:, :, 1], 0.0, 1.0)
    at_level = jnp.minimum(fields[:, :, 0] - fields[:, :, 1] * heights[:, None], levels[:, None])
    h00, h10 = 2 * t ** 3 - 3 * t ** 2 + 1, t ** 3 - 2 * t ** 2 + t
    h01, h11 = -2 * t ** 3 + 3 * t ** 2, t ** 3 - t ** 2
    hermite = (h00 * at_level[0] + h10 * span * slope[0] + h01 * at_level[1]
               + h11 * span * slope[1])
    first = at_level[0] + slope[0] * (z0 - vertical)
    last = at_level[1] + slope[1] * (z1 - vertical)
    depth = jnp.where(vertical > z0, first, jnp.where(vertical < z1, last, hermite))
    value, rate = fields[:, :, _VALUES], fields[:, :, _RATES]
    # field by field: an expression over all fields, sliced by each consumer, is what
    # XLA fuses into every consumer whole (five times the work)
    geometry = tuple(h00 * value[0, :, k] + h10 * span * rate[0, :, k] + h01 * value[1, :, k]
                     + h11 * span * rate[1, :, k] for k in range(value.shape[-1]))
    depth, *geometry = computed_once(depth, *geometry)  # read by most of the force laws
    return depth, tuple(geometry)


@traced_once
def table_patches(table: ContactTable, wheel, track, wheelset_position, wheelset_rotation, side,
                  deflection=None) -> ContactPatches:
    """Contact patches of one wheel on ``track``'s rails from ``table`` (built for that wheel
    and those rails) instead of the search: the same
    :class:`ContactPatches` as :func:`jaxrail.contact.search_wheel` (leading shape
    ``(P,)``), each patch's penetration interpolated between the approach levels in the
    wheel's vertical position (:func:`_along_levels`). ``deflection``: as
    :func:`~jaxrail.contact.search_wheel`'s."""
    side = jnp.asarray(side, dtype=jnp.float64)
    (lateral, vertical, yaw, roll, s_rail, rail_origin, rail_axes, origin,
     frame) = relative_pose(track, table.radius, wheelset_position, wheelset_rotation, side,
                            deflection)
    side_index = jnp.where(side > 0.0, 0, 1).astype(jnp.int32)
    slots, count = len(table.surfaces), table.shape[4]
    starts, size, weight = _pose_weights(table, lateral, yaw, roll)
    zero = jnp.zeros((), jnp.int32)
    heights = window_map(_weighted_nodes, table.heights, (side_index, *starts, zero),
                         (1, *size, count), weight)
    two = _two_levels(heights, vertical)
    fields = window_map(_weighted_levels, table.rows, (side_index, two[0], *starts, zero),
                        (1, 2, *size, table.rows.shape[-1]), weight)
    fields = fields.reshape(2, slots, len(FIELDS))
    depth, interpolated = _along_levels(heights[two], fields, vertical,
                                        jnp.asarray(table.grid.levels)[two])
    y_deepest, centre, breadth, rail_from_wheel, curvature = interpolated
    y_wheel, _ = wide_point(y_deepest, centre, breadth)  # as the search places it
    y_rail = y_wheel + rail_from_wheel
    active = depth > 0.0
    penetration = jnp.where(active, depth, 0.0)
    surfaces = np.asarray(table.surfaces)

    def geometry_at(surface, yw, yr):
        # the wheel point as the search places it on the wheel in its actual pose
        point, s_wheel = wheel_surface_point(surface, wheel.nominal_radius, yw, origin, frame,
                                             side)
        dx = (point - rail_origin) @ rail_axes[:, 0]
        return dict(wheel_point=point, s_wheel=s_wheel, dx=dx,
                    **contact_geometry(surface, track.rails.profile, wheel.nominal_radius, yw,
                                       yr, dx, rail_origin, rail_axes, side))

    parts = []
    for k, surface in enumerate(wheel.surfaces):  # each surface's slots (contiguous)
        mine = np.flatnonzero(surfaces == k)
        parts.append(jax.vmap(lambda yw, yr: geometry_at(surface, yw, yr))(
            y_wheel[mine], y_rail[mine]))
    geometry = jax.tree.map(lambda *x: jnp.concatenate(x), *parts)
    return ContactPatches(
        active=active,
        penetration=penetration,
        surface=jnp.asarray(surfaces, dtype=jnp.int32),
        y_wheel=y_wheel,
        y_rail=y_rail,
        s_rail=jnp.full(y_wheel.shape, s_rail),
        y_track=lateral_from_centre(track, s_rail, side, y_rail, deflection),
        curvature_contact_y=curvature,
        **geometry,
    )
