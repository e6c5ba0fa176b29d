"""Contact tables: the paper's search tabulated over a wheel's pose relative to its rail.

A wheel's contact with a locally straight rail depends only on the wheel's pose in the
rail's frame ``[t n b]`` (:func:`jaxrail.track.rail_frame`). Write ``T`` for the wheel's
taping point (the wheel origin less the nominal radius along the wheel frame's up
axis, eq. 7). The pose is

- ``lateral = n . (T - rail origin)`` [m] (global left positive, for both wheels),
- ``vertical = b . (T - rail origin)`` [m],
- ``roll = arcsin(axle . b)`` [rad] and ``yaw = atan2(-axle . t, axle . n)`` [rad].

A :class:`ContactTable` holds, for each rail (left, right) and each node of a grid in
(lateral, yaw, roll), what the paper's search (:func:`jaxrail.contact.search_wheel`)
finds with the wheel lowered until its deepest patch penetrates each depth of the
approach axis: the wheel's vertical position there and, per patch slot, the signed
depth and its derivative in ``vertical``, the contact point on the wheel and rail
profiles, its longitudinal offset and wheel angle (eqs. 12-13), and the Hertz
curvature of the patch. Patches are
tracked along the lateral axis at build time, so that a slot holds the same patch from
node to node and interpolation never mixes two patches.

Lookups interpolate every field with a quadratic B-spline through the nodes along
lateral, yaw and roll (C1, one block of 3 x 3 x 3 coefficients at every approach
level), then along the levels in the wheel's vertical position: each patch's depth by
cubic Hermite interpolation from its depth and slope at the two levels around it, the
other fields by Catmull-Rom interpolation across the levels. They derive
the rest of :class:`jaxrail.contact.ContactPatches` (contact frame, angle, rolling
radius, profile curvatures) from the profiles at the interpolated points, as the
search does.
"""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..track import project, rail_frame, straight_track
from .search import (HALF_TAPING_DISTANCE, ContactPatches, SearchConfig, contact_geometry,
                     deepest_depth, search_wheel)
from .strip import wheel_frame

FIELDS = ("depth_offset", "depth_slope", "y_wheel", "y_rail", "s_wheel", "dx",
          "curvature_contact_y")
_CLEAR = 1.0e-3  # [m] slots that never hold a patch: this far clear of the rail
# [m] per node: a slot's depth where its patch has gone falls off this fast from the last
# node that held it (a ramp, not a step: the spline through the nodes would ring)
_RAMP = 3.0e-5
# [m] per node: along the lateral axis a gone patch's depth continues its own trend
# (no kink for the spline to ring at), falling by at least this and its last depth,
# at most _RAMP
_RAMP_MIN = 1.0e-6
_CANDIDATE = 1.5e-4  # [m] a found slot deeper than -this is a patch (search: 1e-4)
_TRACK_JUMP = 1.0e-2  # [m] largest move of a patch on the wheel between lateral nodes
_LEVEL_TOLERANCE = 1.0e-7  # [m] on the deepest depth at each approach level (reported)


class Axis(eqx.Module):
    """A uniform grid axis: ``count`` nodes from ``start`` with spacing ``step``."""

    start: float = eqx.field(static=True)
    step: float = eqx.field(static=True)
    count: int = eqx.field(static=True)

    @property
    def nodes(self) -> np.ndarray:
        return self.start + self.step * np.arange(self.count)

    @classmethod
    def span(cls, lo: float, hi: float, step: float) -> "Axis":
        """Nodes covering ``[lo, hi]`` with spacing at most ``step`` (one node if equal)."""
        if hi < lo or step <= 0.0:
            raise ValueError(f"axis needs lo <= hi and step > 0, got {lo}, {hi}, {step}")
        if hi == lo:
            return cls(float(lo), 1.0, 1)
        count = math.ceil((hi - lo) / step - 1e-9) + 1
        return cls(float(lo), (hi - lo) / (count - 1), count)


class TableGrid(eqx.Module):
    """Grid of a contact table: lateral [m], yaw [rad] and roll [rad] axes, and the
    approach axis in the square root of the deepest patch's depth [m^0.5] (the search
    runs at the depths ``approach.nodes ** 2``: denser where a conformal patch's
    contact point moves fastest with the depth, near first contact)."""

    lateral: Axis = Axis.span(-0.016, 0.016, 1.0e-4)
    yaw: Axis = Axis.span(-0.01, 0.01, 0.005)
    roll: Axis = Axis.span(-0.015, 0.015, 0.005)
    approach: Axis = Axis.span(2.0e-3, 1.5e-2, 2.6e-3)

    @property
    def levels(self) -> tuple[float, ...]:
        """Depths [m] of the deepest patch at the approach nodes."""
        return tuple(float(x) ** 2 for x in self.approach.nodes)


class ContactTable(eqx.Module):
    """Tabulated contact of one wheel profile on its rail, both sides.

    Built from ``values`` (2, lateral, yaw, roll, approach, slots + 1, len(FIELDS))
    float64, sides (left, right): quadratic B-spline coefficients along lateral, yaw
    and roll (two more than the nodes along every axis of two or more nodes) of the
    fields of :data:`FIELDS` per patch slot at each approach level, and in the last slot
    the wheel's vertical position at that level (first field). Kept as ``rows``, one
    row per (side, lateral, yaw, roll) node, so that a lookup gathers whole rows from
    the array as it is (reshaping a traced table inside the integrator's loop makes
    XLA:CPU's loop emitters slow); ``values`` gives them back in their shape.

    Fields:
        rows: (2 lateral yaw roll, approach (slots + 1) len(FIELDS)) float64.
        shape: the shape of ``values`` (static).
        grid: the :class:`TableGrid`.
        surfaces: wheel surface index of each slot (static).
        radius: nominal wheel radius [m] that places the taping point.
    """

    rows: jax.Array
    shape: tuple[int, ...] = eqx.field(static=True)
    grid: TableGrid = eqx.field(static=True)
    surfaces: tuple[int, ...] = eqx.field(static=True)
    radius: float = eqx.field(static=True)

    def __init__(self, values, grid: TableGrid, surfaces, radius):
        self.shape = tuple(int(n) for n in values.shape)
        self.rows = jnp.asarray(values).reshape(math.prod(self.shape[:4]), -1)
        self.grid, self.surfaces, self.radius = grid, tuple(surfaces), float(radius)

    @property
    def values(self) -> jax.Array:
        """The coefficients in their shape (see the class docstring)."""
        return self.rows.reshape(self.shape)


def relative_pose(track, rail_offset, radius, wheelset_position, wheelset_rotation, side):
    """Pose of one wheel relative to its rail (module docstring).

    Returns ``(lateral, vertical, yaw, roll, s_rail, rail_origin, rail_axes)``: the four
    pose coordinates [m, m, rad, rad] and the rail section's arc length [m], origin (3,)
    and axes (3, 3)."""
    axle = wheelset_rotation[:, 1]
    wheel_origin = wheelset_position + side * HALF_TAPING_DISTANCE * axle
    s_rail = project(track, wheel_origin)
    rail_origin, rail_axes = rail_frame(track, s_rail, side, rail_offset)
    frame = wheel_frame(axle, rail_axes[:, 0])
    taping = wheel_origin - radius * frame.up - rail_origin
    local = rail_axes.T @ axle
    roll = jnp.arcsin(jnp.clip(local[2], -1.0, 1.0))
    yaw = jnp.arctan2(-local[0], local[1])
    return (taping @ rail_axes[:, 1], taping @ rail_axes[:, 2], yaw, roll, s_rail, rail_origin,
            rail_axes)


def _pose_on_straight(track, rail_offset, radius, lateral, vertical, yaw, roll, side):
    """Wheelset pose on a straight level ``track`` at s = 50 m whose ``side`` wheel has
    this relative pose."""
    rail_origin, rail_axes = rail_frame(track, 50.0, side, rail_offset)
    cy, sy, cr, sr = jnp.cos(yaw), jnp.sin(yaw), jnp.cos(roll), jnp.sin(roll)
    rotation_local = jnp.array([[cy, -sy * cr, sy * sr], [sy, cy * cr, -cy * sr],
                                [0.0, sr, cr]])  # Rz(yaw) Rx(roll)
    rotation = rail_axes @ rotation_local
    axle = rotation[:, 1]
    up = wheel_frame(axle, rail_axes[:, 0]).up
    wheel_origin = rail_origin + lateral * rail_axes[:, 1] + vertical * rail_axes[:, 2] + radius * up
    return wheel_origin - side * HALF_TAPING_DISTANCE * axle, rotation


def _node(wheel, rail, rail_offset, lateral, yaw, roll, side, config, radius, levels):
    """The search at one node (lateral [m], yaw [rad], roll [rad]) of the ``side`` rail
    with the wheel lowered until its deepest patch penetrates each of the ``levels`` [m].

    Returns ``(found (L, P), values (L, P, len(FIELDS)), depth (L, P), heights (L,),
    miss)``: the slots holding a patch, their fields, their signed depths, the wheel's
    vertical position [m] at each level, and the largest error [m] of the deepest depth
    against its level."""
    track = straight_track(100.0)
    first_strip = jnp.stack([config.strip_grid(surface)[0] for surface in wheel.surfaces])

    def pose(vertical):
        return _pose_on_straight(track, rail_offset, radius, lateral, vertical, yaw, roll, side)

    def residual(z, depth):
        return deepest_depth(wheel, rail, track, rail_offset, *pose(z), side, config) - depth

    def height(depth, bracket, steps):
        """Safeguarded Newton on the vertical position for ``depth`` in ``bracket`` (the
        deepest depth falls monotonically as the wheel rises); returns the position and
        the depth's residual [m]."""
        def step(state, _):
            z, lo, hi = state
            f, df = jax.jvp(lambda v: residual(v, depth), (z,), (jnp.ones_like(z),))
            lo, hi = jnp.where(f > 0.0, z, lo), jnp.where(f > 0.0, hi, z)
            newton = z - f / jnp.where(df < -1e-3, df, -1e-3)
            inside = (newton > lo) & (newton < hi)
            return (jnp.where(inside, newton, 0.5 * (lo + hi)), lo, hi), None
        lo, hi = bracket
        (z, _, _), _ = jax.lax.scan(step, (0.5 * (lo + hi), lo, hi), None, length=steps)
        return z, residual(z, depth)

    def slots(z):
        patches = search_wheel(wheel, rail, track, rail_offset, *pose(z), side, config)
        geometric = jnp.einsum("pi,pi->p", patches.rail_point - patches.wheel_point, patches.normal)
        return jnp.where(patches.active, patches.penetration, geometric), patches

    def level(z):
        (signed, patches), (d_signed, _) = jax.jvp(slots, (z,), (jnp.ones_like(z),))
        # A slot is a patch when the search found it (active) or it is a near candidate;
        # empty slots point at the first strip of their surface.
        empty = patches.y_wheel == first_strip[patches.surface]
        found = patches.active | ((signed > -_CANDIDATE) & (signed <= 0.0) & ~empty)
        slope = -d_signed  # the depth grows as the wheel comes down
        values = jnp.stack([signed + slope * z, slope, patches.y_wheel, patches.y_rail,
                            patches.s_wheel, patches.dx, patches.curvature_contact_y], axis=-1)
        return found, values

    heights, misses = [], []
    z, miss = height(levels[0], (-0.03, 0.03), 24)
    for k, depth in enumerate(levels):
        if k:  # deeper: lower, by at most ten times the extra depth
            z, miss = height(depth, (z - 10.0 * (depth - levels[k - 1]), z), 10)
        heights.append(jax.lax.stop_gradient(z))
        misses.append(miss)
    heights = jnp.stack(heights)
    found, values = jax.vmap(level)(heights)
    depth = values[..., 0] - values[..., 1] * heights[:, None]
    return found, values, depth, heights, jnp.max(jnp.abs(jnp.stack(misses)))


@eqx.filter_jit
def _run_nodes(wheel, rail, rail_offset, nodes, side, config, radius, levels):
    """:func:`_node` vmapped over ``nodes`` (N, 3) (one compilation for both sides and
    every chunk)."""
    return jax.vmap(lambda x: _node(wheel, rail, rail_offset, x[0], x[1], x[2], side, config,
                                    radius, levels))(nodes)


def _distance(a, b):
    """How far apart two patches' values (F,) are [m]: their wheel coordinates, depth
    offsets (ten times: twin maxima sharing a run are close on the wheel but not in
    depth) and depth slopes (a millimetre per unit)."""
    return (abs(a[2] - b[2]) + 10.0 * abs(a[0] - b[0]) + 1.0e-3 * abs(a[1] - b[1]))


def _track_line(found, values, depth, surfaces):
    """Slot-consistent values (L, P, F) and owned flags (L, P) of one lateral line:
    patches tracked along the lateral axis by their wheel coordinate, each surface's
    slots assigned in order of birth; empty slots continue the nearest value of their
    track, falling off as :func:`_fall` says."""
    n, p, _ = values.shape
    out = np.zeros_like(values)
    owner = np.full((n, p), -1)  # track id per node and slot
    held = np.full((n, p), -np.inf)  # depth of the patch in each slot and node
    tracks = []  # (surface, last values, last node) per track id
    slot_of = {}
    for i in range(n):
        used = set()
        newcomers = []
        for k in sorted(np.flatnonzero(found[i]), key=lambda k: -depth[i, k]):
            surface = surfaces[k]
            best, distance = None, _TRACK_JUMP
            for t, (s, last, last_i) in enumerate(tracks):
                if s == surface and last_i == i - 1 and t not in used:
                    gap = _distance(last, values[i, k])
                    if gap < distance:
                        best, distance = t, gap
            if best is None:
                newcomers.append(k)
                continue
            used.add(best)
            tracks[best] = (surface, values[i, k], i)
            owner[i, slot_of[best]] = best
            out[i, slot_of[best]] = values[i, k]
            held[i, slot_of[best]] = depth[i, k]
        for k in newcomers:  # deepest first
            surface = surfaces[k]
            free = [j for j in range(p) if surfaces[j] == surface
                    and owner[i, j] < 0 and (i == 0 or owner[i - 1, j] < 0)]
            if not free:
                # more patches than slots: the shallowest patch gives up its slot
                mine = [j for j in range(p) if surfaces[j] == surface and owner[i, j] >= 0]
                j = min(mine, key=lambda j: held[i, j]) if mine else None
                if j is None or held[i, j] >= depth[i, k]:
                    continue
                free = [j]
            tracks.append((surface, values[i, k], i))
            slot_of[len(tracks) - 1] = free[0]
            owner[i, free[0]] = len(tracks) - 1
            out[i, free[0]] = values[i, k]
            held[i, free[0]] = depth[i, k]
    clear = np.zeros(len(FIELDS))
    clear[0] = -_CLEAR
    for j in range(p):
        have = np.flatnonzero(owner[:, j] >= 0)
        if have.size == 0:
            out[:, j] = clear
            continue
        for i in np.flatnonzero(owner[:, j] < 0):
            near = have[np.argmin(np.abs(have - i))]
            out[i, j] = out[near, j]
            out[i, j, 0] -= min(_CLEAR, _fall(out[:, j, 0], owner[:, j], held[:, j], near, i)
                                * abs(i - near))
    return out, owner >= 0


def _fall(offset, owner, held, near, i):
    """How fast [m per node] a slot's depth offset falls from ``near``, the last node
    whose patch it held, toward ``i``: the patch's own trend over the node before
    ``near`` when the same patch was there (a continued line has no kink for the
    spline to ring at), at least its depth at ``near`` and ``_RAMP_MIN``, at most
    ``_RAMP``."""
    inner = near - 1 if i > near else near + 1
    trend = 0.0
    if 0 <= inner < len(offset) and owner[inner] == owner[near]:
        trend = offset[inner] - offset[near]
    return float(np.clip(max(trend, held[near]), _RAMP_MIN, _RAMP))


def _match(found, values, depth, reference, owned, surfaces, rigid):
    """Values (P, F) of a node in the slots of an already assigned neighbour
    (``reference`` (P, F), ``owned`` (P,)): each patch, deepest first, goes to the owned
    slot of its surface nearest on the wheel, a newcomer to a free slot. A slot left
    empty keeps the neighbour's values: as they are when ``rigid`` (the next deeper
    approach level: its depth offset and slope continue the patch as the wheel rises),
    else one ramp step (``_RAMP``) clear of it. Returns the values and the owned flags."""
    out, taken = reference.copy(), np.zeros(len(owned), dtype=bool)
    for k in sorted(np.flatnonzero(found), key=lambda k: -depth[k]):
        mine = [j for j in range(len(owned)) if surfaces[j] == surfaces[k] and not taken[j]]
        near = [j for j in mine if owned[j]]
        if near:
            j = min(near, key=lambda j: _distance(reference[j], values[k]))
        elif mine:
            j = mine[0]
        else:
            continue
        out[j], taken[j] = values[k], True
    if not rigid:
        out[~taken & owned, 0] -= _RAMP
        return out, taken
    return out, owned | taken


def _assign_slots(found, values, depth, surfaces):
    """Slot-consistent values (L, Y, R, A, P, F) of a whole grid (lateral, yaw, roll,
    approach): patches tracked along the lateral axis on the central yaw and roll line
    at the deepest approach, then every other node matched to its neighbour toward that
    line (shallower levels to the deeper one, then outward in yaw, then in roll)."""
    n_lat, n_yaw, n_roll, n_app = found.shape[:4]
    out = np.empty_like(values)
    owned = np.zeros(found.shape, dtype=bool)
    jc, kc, deep = n_yaw // 2, n_roll // 2, n_app - 1

    def match(i, j, k, m, ref, rigid):
        out[i, j, k, m], owned[i, j, k, m] = _match(
            found[i, j, k, m], values[i, j, k, m], depth[i, j, k, m], out[(i,) + ref],
            owned[(i,) + ref], surfaces, rigid)

    out[:, jc, kc, deep], owned[:, jc, kc, deep] = _track_line(
        found[:, jc, kc, deep], values[:, jc, kc, deep], depth[:, jc, kc, deep], surfaces)
    outward = lambda centre, count: [x for x in sorted(range(count), key=lambda x: abs(x - centre))  # noqa: E731
                                     if x != centre]
    for i in range(n_lat):
        for m in range(deep - 1, -1, -1):
            match(i, jc, kc, m, (jc, kc, m + 1), True)
        for j in outward(jc, n_yaw):
            toward = j - 1 if j > jc else j + 1
            for m in range(n_app):
                match(i, j, kc, m, (toward, kc, m), False)
        for k in outward(kc, n_roll):
            toward = k - 1 if k > kc else k + 1
            for j in range(n_yaw):
                for m in range(n_app):
                    match(i, j, k, m, (j, toward, m), False)
    return out


def build_contact_table(wheel, rail, rail_offset, config: SearchConfig = SearchConfig(),
                        grid: TableGrid = TableGrid(), chunk: int = 256,
                        progress=None) -> tuple[ContactTable, dict]:
    """Run the paper's search at every node of ``grid`` for both rails.

    Returns the table and diagnostics: ``nodes``, and ``level_misses``, the nodes where
    the deepest depth could not be brought within 0.1 um of an approach level (the
    refined depth of the search jumps in a few poses where the contact moves across the
    S1002 throat), with the largest miss ``worst_level_miss_m``; such a node keeps the
    search's data at the height reached.

    Arguments:
        wheel, rail, rail_offset, config: as :func:`jaxrail.contact.search_wheel`.
        grid: the :class:`TableGrid`.
        chunk: nodes per compiled batch.
        progress: optional callable ``(done, total)`` for a progress bar.
    """
    radius = float(wheel.nominal_radius)
    surfaces = tuple(k for k, _ in enumerate(wheel.surfaces) for _ in range(config.max_patches))
    lateral, yaw, roll = grid.lateral.nodes, grid.yaw.nodes, grid.roll.nodes
    nodes = np.stack(np.meshgrid(lateral, yaw, roll, indexing="ij"), axis=-1).reshape(-1, 3)
    total, done, worst_miss, misses = 2 * len(nodes), 0, 0.0, 0
    sides = []
    levels = grid.levels
    for side in (1.0, -1.0):
        found, values, depth, heights = [], [], [], []
        for start in range(0, len(nodes), chunk):
            batch = nodes[start:start + chunk]
            padded = np.concatenate([batch, np.repeat(batch[-1:], chunk - len(batch), 0)])
            f, v, d, z, miss = _run_nodes(wheel, rail, float(rail_offset), jnp.asarray(padded),
                                          jnp.asarray(side), config, radius, levels)
            found.append(np.asarray(f)[:len(batch)])
            values.append(np.asarray(v)[:len(batch)])
            depth.append(np.asarray(d)[:len(batch)])
            heights.append(np.asarray(z)[:len(batch)])
            miss = np.asarray(miss)[:len(batch)]
            worst_miss = max(worst_miss, float(np.max(miss)))
            misses += int(np.sum(miss > _LEVEL_TOLERANCE))
            done += len(batch)
            if progress is not None:
                progress(done, total)
        shape = (len(lateral), len(yaw), len(roll), grid.approach.count)
        found = np.concatenate(found).reshape(shape + (len(surfaces),))
        values = np.concatenate(values).reshape(shape + (len(surfaces), len(FIELDS)))
        depth = np.concatenate(depth).reshape(shape + (len(surfaces),))
        heights = np.concatenate(heights).reshape(shape)
        tracked = _assign_slots(found, values, depth, surfaces)
        # the wheel's vertical position at each level as one more slot (first field)
        extra = np.zeros(shape + (1, len(FIELDS)))
        extra[..., 0, 0] = heights
        tracked = np.concatenate([tracked, extra], axis=-2)
        sides.append(tracked)
    diagnostics = {"nodes": total, "level_misses": misses, "worst_level_miss_m": worst_miss}
    return ContactTable(jnp.asarray(_prefilter(np.stack(sides), grid)), grid, surfaces,
                        radius), diagnostics


def _pose_axes(grid: TableGrid):
    return (grid.lateral, grid.yaw, grid.roll)


def _spline_matrix(count):
    """(count + 2, count + 2) system for the coefficients of a uniform quadratic
    B-spline through ``count`` node values, with a zero third difference of the
    coefficients at both ends (rows 0 and -1), so that quadratics are reproduced
    exactly up to the ends (a yaw axis of five nodes is mostly ends); two nodes give
    the line through them."""
    a = np.zeros((count + 2, count + 2))
    end = (-1.0, 3.0, -3.0, 1.0) if count > 2 else (1.0, -2.0, 1.0)  # two nodes: a line
    a[0, :len(end)] = end
    a[-1, -len(end):] = end
    for i in range(count):
        a[i + 1, i:i + 3] = (0.125, 0.75, 0.125)
    return a


def _prefilter(values, grid: TableGrid):
    """Quadratic B-spline coefficients (2, lateral + 2, yaw + 2, roll + 2, approach, P, F)
    of ``values`` (2, lateral, yaw, roll, approach, P, F) along the pose axes: the spline
    through every node value (C1, third-order accurate); one-node axes stay as they
    are. The approach axis keeps its node values (:func:`table_patches` interpolates
    along it in the wheel's vertical position)."""
    for dim, axis in enumerate(_pose_axes(grid), start=1):
        if axis.count < 2:
            continue
        moved = np.moveaxis(values, dim, 0)
        rhs = np.concatenate([np.zeros((1,) + moved.shape[1:]), moved,
                              np.zeros((1,) + moved.shape[1:])])
        solved = np.linalg.solve(_spline_matrix(axis.count), rhs.reshape(len(rhs), -1))
        values = np.moveaxis(solved.reshape(rhs.shape), 0, dim)
    return values


def _spline_weights(axis: Axis, x):
    """Start of the 3-coefficient block and the quadratic B-spline weights of ``x``
    (clamped to the axis' span); a one-node axis gives (0, [1])."""
    if axis.count == 1:
        return jnp.zeros((), dtype=jnp.int32), jnp.ones((1,))
    u = jnp.clip((x - axis.start) / axis.step, 0.0, axis.count - 1.0)
    i = jnp.clip(jnp.round(u), 0, axis.count - 1)
    t = u - i
    w = jnp.stack([0.5 * (0.5 - t) ** 2, 0.75 - t * t, 0.5 * (0.5 + t) ** 2])
    return i.astype(jnp.int32), w


def interpolate(table: ContactTable, side_index, lateral, yaw, roll):
    """Fields (approach nodes, slots + 1, len(FIELDS)) at a pose from the quadratic
    B-spline of the table along lateral, yaw and roll (C1): the 3 x 3 x 3 block of
    coefficients around the pose, 27 of the table's ``rows`` in one gather (several
    times cheaper than a 7-D slice), weighted by the product of the axes' weights."""
    shape = table.shape
    index = jnp.asarray(side_index, dtype=jnp.int32)
    weight = jnp.ones(())
    for axis, x, count in zip(_pose_axes(table.grid), (lateral, yaw, roll), shape[1:4]):
        start, w = _spline_weights(axis, x)
        offsets = jnp.arange(len(w), dtype=jnp.int32)
        index = (index * count)[..., None] + start + offsets
        weight = weight[..., None] * w
    block = table.rows[index.reshape(-1)]
    return (weight.reshape(-1) @ block).reshape(shape[4:])


def _along_levels(heights, fields, vertical, levels):
    """Per slot the depth [m] and the other fields at the wheel's ``vertical`` position
    [m] from their values at the approach levels (``heights`` (L,) decreasing, the wheel
    lower at deeper levels; ``fields`` (L, P, F)): the depth by cubic Hermite
    interpolation in the vertical position between the two levels around it, from each
    level's depth and slope (C1; beyond the first and last level, that level's line),
    the other fields by Catmull-Rom interpolation in the level index."""
    count = heights.shape[0]
    below = jnp.sum(heights > vertical)  # levels above the wheel's position
    i = jnp.clip(below - 1, 0, count - 2)
    z0, z1 = heights[i], heights[i + 1]
    t = jnp.clip((z0 - vertical) / (z0 - z1), 0.0, 1.0)
    # No patch is deeper than the level's deepest depth, and none deepens faster than
    # the wheel comes down (guards against nodes where the search's refined depth jumps)
    slope = jnp.clip(fields[:, :, 1], 0.0, 1.0)
    at_level = jnp.minimum(fields[:, :, 0] - fields[:, :, 1] * heights[:, None],
                           levels[:, None])
    span = z0 - z1  # the wheel comes down by this from level i to i + 1
    h00, h10 = 2 * t ** 3 - 3 * t ** 2 + 1, t ** 3 - 2 * t ** 2 + t
    h01, h11 = -2 * t ** 3 + 3 * t ** 2, t ** 3 - t ** 2
    hermite = (h00 * at_level[i] + h10 * span * slope[i] + h01 * at_level[i + 1]
               + h11 * span * slope[i + 1])
    first = at_level[0] + slope[0] * (heights[0] - vertical)
    last = at_level[-1] + slope[-1] * (heights[-1] - vertical)
    depth = jnp.where(vertical > heights[0], first,
                      jnp.where(vertical < heights[-1], last, hermite))
    # the other fields: Catmull-Rom in the level index (C1 in t, third order)
    index = jnp.clip(i + jnp.arange(-1, 3), 0, count - 1)
    w = 0.5 * jnp.stack([-t ** 3 + 2 * t ** 2 - t, 3 * t ** 3 - 5 * t ** 2 + 2,
                         -3 * t ** 3 + 4 * t ** 2 + t, t ** 3 - t ** 2])
    return depth, jnp.tensordot(w, fields[index], axes=1)


def table_patches(table: ContactTable, wheel, rail, track, rail_offset, wheelset_position,
                  wheelset_rotation, side) -> ContactPatches:
    """Contact patches of one wheel from ``table`` instead of the search: the same
    :class:`ContactPatches` as :func:`jaxrail.contact.search_wheel` (leading shape
    ``(P,)``), each patch's penetration interpolated between the approach levels in the
    wheel's vertical position (:func:`_along_levels`)."""
    side = jnp.asarray(side, dtype=jnp.float64)
    lateral, vertical, yaw, roll, s_rail, rail_origin, rail_axes = relative_pose(
        track, rail_offset, table.radius, wheelset_position, wheelset_rotation, side)
    side_index = jnp.where(side > 0.0, 0, 1).astype(jnp.int32)
    slots = len(table.surfaces)
    levels = interpolate(table, side_index, lateral, yaw, roll)
    depth, fields = _along_levels(levels[:, slots, 0], levels[:, :slots], vertical,
                                  jnp.asarray(table.grid.levels))
    _, _, y_wheel, y_rail, s_wheel, dx, curvature = (fields[:, k] for k in range(len(FIELDS)))
    active = depth > 0.0
    penetration = jnp.where(active, depth, 0.0)
    surfaces = np.asarray(table.surfaces)
    parts = []
    for k, surface in enumerate(wheel.surfaces):  # each surface's slots (contiguous)
        mine = np.flatnonzero(surfaces == k)
        parts.append(jax.vmap(lambda yw, yr, x: contact_geometry(
            surface, rail, wheel.nominal_radius, yw, yr, x, rail_origin, rail_axes, side))(
            y_wheel[mine], y_rail[mine], dx[mine]))
    geometry = jax.tree.map(lambda *x: jnp.concatenate(x), *parts)
    return ContactPatches(
        active=active,
        penetration=penetration,
        surface=jnp.asarray(surfaces, dtype=jnp.int32),
        y_wheel=y_wheel,
        s_wheel=s_wheel,
        dx=dx,
        y_rail=y_rail,
        s_rail=jnp.full(y_wheel.shape, s_rail),
        y_track=side * (rail_offset + y_rail),
        wheel_point=geometry["rail_point"] - penetration[:, None] * geometry["normal"],
        curvature_contact_y=curvature,
        **geometry,
    )
