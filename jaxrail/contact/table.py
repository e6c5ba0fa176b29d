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
depth, the parts the search places the contact point from (the patch's deepest point,
the centre and breadth of its interpenetration), the rail point's offset from it on the
profiles and the Hertz curvature of the patch, each with its derivative in
``vertical`` (forward-mode, through the search). Patches are tracked along the lateral
axis at build time (in order along the wheel: two patches of one surface cannot pass
each other), so that a slot holds the same patch from node to node and interpolation
does not mix two patches.

Lookups interpolate every field with a quadratic B-spline through the nodes along
lateral, yaw and roll (C1, one block of 3 x 3 x 3 coefficients), first the wheel's
vertical position at the levels, then the slots at the two levels around the wheel's
actual position, and between them by cubic Hermite interpolation in the vertical
position from each field's values and derivatives there. They place the contact point
from its parts as the search does (:func:`jaxrail.contact.patches.wide_point`): on the
conformal UIC60 1:20 tread the point moves 15-35 um per um of depth and its rate jumps
where the blend starts and ends, which the parts do not. They derive the rest of
:class:`jaxrail.contact.ContactPatches` as the search does, from the wheel's actual
pose and the profiles at the interpolated points: the wheel point on the wheel's strip
(eq. 12; the creepages are taken between it and the rail point, so its height matters
to 1e-5 of the rolling radius), its longitudinal offset, the contact frame, angle,
rolling radius and profile curvatures.
"""

import itertools
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..track import rail_frame, straight_track
from ..track.rails import HALF_TAPING_DISTANCE, rail_displacement, rail_under_wheel, wheel_origin
from .patches import wide_point
from .search import (ContactPatches, SearchConfig, contact_geometry,
                     deepest_depth, search_wheel_parts)
from .strip import wheel_frame, wheel_surface_point

# A slot's contact point as the search makes it (its deepest point, the centre and
# breadth of its interpenetration: the point is blended from the first two by the
# breadth), the rail point's offset from it on the profiles and the Hertz curvature
GEOMETRY = ("y_deepest", "centre", "breadth", "rail_from_wheel", "curvature_contact_y")
# each slot's depth as a line in the wheel's height, the geometry, and the geometry's
# rates [per m the wheel comes down]: the tangents of the interpolation across levels
FIELDS = ("depth_offset", "depth_slope") + GEOMETRY + tuple(f"{name}_rate" for name in GEOMETRY)
_VALUES = slice(2, 2 + len(GEOMETRY))  # the geometry's columns of FIELDS
_RATES = slice(2 + len(GEOMETRY), len(FIELDS))  # and its rates'
_WHERE = len(FIELDS)  # at build time only: the contact point y_wheel [m], for tracking
_CLEAR = 1.0e-3  # [m] slots that never hold a patch: this far clear of the rail
# [m] per node: where its patch has gone, a slot's depth falls below the rail within one
# node and on by the patch's own trend (no kink for the spline to ring at), at least
# _RAMP_MIN and at most _RAMP; across yaw and roll by _RAMP
_RAMP = 3.0e-5
_RAMP_MIN = 1.0e-6
_CANDIDATE = 1.5e-4  # [m] a found slot deeper than -this is a patch (search: 1e-4)
_TRACK_JUMP = 1.0e-2  # [m] largest move of a patch on the wheel between lateral nodes
_MATCH_LIMIT = 1.0  # [m] between levels and yaw or roll nodes: pair as many as there are
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
    contact point moves fastest with the depth, near first contact). Conformal contact
    is sensitive to roll (on UIC60 1:20 the S1002 contact point moves up to 1.5 mm per
    mrad): half-way between the default roll nodes the table is up to 0.34 mm (1:20)
    and 0.054 mm (1:40) off the search, with a 2.5 mrad step 0.021 and 0.003 mm
    (docs/contact-table.md)."""

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
    the wheel's vertical position at that level (first field). Kept as ``heights``, one
    row of levels per (side, lateral, yaw, roll) node, and ``rows``, one row of slots
    per node and level, so that a lookup gathers whole rows from the arrays as they are
    (reshaping a traced table inside the integrator's loop makes XLA:CPU's loop emitters
    slow), and only the levels it needs; ``values`` gives them back in their shape.

    Fields:
        rows: (2 lateral yaw roll approach, slots len(FIELDS)) float64.
        heights: (2 lateral yaw roll, approach) float64 [m].
        shape: the shape of ``values`` (static).
        grid: the :class:`TableGrid`.
        surfaces: wheel surface index of each slot (static).
        radius: nominal wheel radius [m] that places the taping point.
    """

    rows: jax.Array
    heights: jax.Array
    shape: tuple[int, ...] = eqx.field(static=True)
    grid: TableGrid = eqx.field(static=True)
    surfaces: tuple[int, ...] = eqx.field(static=True)
    radius: float = eqx.field(static=True)

    def __init__(self, values, grid: TableGrid, surfaces, radius):
        self.shape = tuple(int(n) for n in values.shape)
        values = jnp.asarray(values)
        nodes, slots = math.prod(self.shape[:4]), self.shape[5] - 1
        self.rows = values[..., :slots, :].reshape(nodes * self.shape[4], -1)
        self.heights = values[..., slots, 0].reshape(nodes, self.shape[4])
        self.grid, self.surfaces, self.radius = grid, tuple(surfaces), float(radius)

    @property
    def values(self) -> jax.Array:
        """The coefficients in their shape (see the class docstring)."""
        slots = self.rows.reshape(self.shape[:5] + (self.shape[5] - 1, self.shape[6]))
        last = jnp.zeros(self.shape[:5] + (1, self.shape[6])).at[..., 0, 0].set(
            self.heights.reshape(self.shape[:5]))
        return jnp.concatenate([slots, last], axis=-2)


def relative_pose(track, rail_offset, radius, wheelset_position, wheelset_rotation, side):
    """Pose of one wheel relative to its rail (module docstring).

    Returns ``(lateral, vertical, yaw, roll, s_rail, rail_origin, rail_axes, wheel_origin,
    frame)``: the four pose coordinates [m, m, rad, rad], the rail section's arc length
    [m], origin (3,) and axes (3, 3), and the wheel's origin (3,) and
    :class:`~jaxrail.contact.strip.WheelFrame`."""
    axle = wheelset_rotation[:, 1]
    origin = wheel_origin(wheelset_position, wheelset_rotation, side)
    s_rail, rail_origin, rail_axes = rail_under_wheel(track, rail_offset, origin, side)
    frame = wheel_frame(axle, rail_axes[:, 0])
    taping = origin - radius * frame.up - rail_origin
    local = rail_axes.T @ axle
    roll = jnp.arcsin(jnp.clip(local[2], -1.0, 1.0))
    yaw = jnp.arctan2(-local[0], local[1])
    return (taping @ rail_axes[:, 1], taping @ rail_axes[:, 2], yaw, roll, s_rail, rail_origin,
            rail_axes, origin, frame)


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
    origin = rail_origin + lateral * rail_axes[:, 1] + vertical * rail_axes[:, 2] + radius * up
    return origin - side * HALF_TAPING_DISTANCE * axle, rotation


def _node(wheel, rail, rail_offset, lateral, yaw, roll, side, config, radius, levels):
    """The search at one node (lateral [m], yaw [rad], roll [rad]) of the ``side`` rail
    with the wheel lowered until its deepest patch penetrates each of the ``levels`` [m].

    Returns ``(found (L, P), values (L, P, len(FIELDS) + 1), depth (L, P), heights (L,),
    miss)``: the slots holding a patch, their fields and contact point (``_WHERE``),
    their signed depths, the wheel's
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
        patches, parts = search_wheel_parts(wheel, rail, track, rail_offset, *pose(z), side, config)
        geometric = jnp.einsum("pi,pi->p", patches.rail_point - patches.wheel_point, patches.normal)
        named = dict(parts, rail_from_wheel=patches.y_rail - patches.y_wheel,
                     curvature_contact_y=patches.curvature_contact_y)
        geometry = jnp.stack([named[name] for name in GEOMETRY], -1)
        return jnp.where(patches.active, patches.penetration, geometric), geometry, patches

    def level(z):
        (signed, geometry, patches), (d_signed, d_geometry, _) = jax.jvp(
            slots, (z,), (jnp.ones_like(z),))
        # A slot is a patch when the search found it (active) or it is a near candidate;
        # empty slots point at the first strip of their surface.
        empty = patches.y_wheel == first_strip[patches.surface]
        found = patches.active | ((signed > -_CANDIDATE) & (signed <= 0.0) & ~empty)
        slope = -d_signed  # the depth grows as the wheel comes down
        values = jnp.concatenate([jnp.stack([signed + slope * z, slope], -1), geometry, -d_geometry,
                                  patches.y_wheel[:, None]], axis=-1)
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
    """How far apart two patches are [m], each given as (wheel coordinate [m], depth [m],
    depth slope): their wheel coordinates, depths (ten times: twin maxima sharing a run
    are close on the wheel but not in depth) and slopes (a millimetre per unit). Depths,
    not depth offsets: an offset moves with the wheel's height, which differs from node
    to node (by tenths of a millimetre per node in flange contact)."""
    return abs(a[0] - b[0]) + 10.0 * abs(a[1] - b[1]) + 1.0e-3 * abs(a[2] - b[2])


def _key(value, depth):
    """(wheel coordinate, depth, depth slope) of a patch's values (F + 1,) and depth [m]."""
    return np.array([value[_WHERE], depth, value[1]])


def _pair(old, new, cost, limit):
    """Order-preserving pairs ``(i, j)`` of ``old[i]`` with ``new[j]`` (both sorted along
    the wheel): two patches of one surface are separate maxima of the penetration and
    cannot pass each other on the wheel without merging, so the k-th paired old patch
    goes to the k-th paired new one. Of all such pairings, the one with the least
    ``cost(i, j)`` plus ``limit / 2`` per patch left unpaired; pairs costing ``limit`` or
    more are not allowed."""
    best, best_cost = [], 0.5 * limit * (len(old) + len(new))
    for r in range(1, min(len(old), len(new)) + 1):
        for olds in itertools.combinations(range(len(old)), r):
            for news in itertools.combinations(range(len(new)), r):
                costs = [cost(i, j) for i, j in zip(olds, news)]
                if max(costs) >= limit:
                    continue
                total = sum(costs) + 0.5 * limit * (len(old) + len(new) - 2 * r)
                if total < best_cost:
                    best, best_cost = list(zip(olds, news)), total
    return best


def _track_line(found, values, depth, surfaces, heights):
    """Slot-consistent values (L, P, F) and owned flags (L, P) of one lateral line:
    patches tracked along the lateral axis (:func:`_pair`, each track's next wheel
    coordinate, depth and slope also predicted from its last two nodes: on a conformal
    tread patches move several times their spacing per millimetre of shift), each
    surface's slots assigned in order of birth; empty slots continue the nearest value of
    their track, its depth (at each node's own ``heights`` (L,) [m]: the wheel's height
    changes from node to node) falling off as :func:`_fall` says."""
    n, p, _ = values.shape
    out = np.zeros_like(values)
    owner = np.full((n, p), -1)  # track id per node and slot
    held = np.full((n, p), -np.inf)  # depth of the patch in each slot and node
    tracks = []  # per track id: [surface, slot, last key, key before, last node] (_key)
    for i in range(n):
        newcomers = []
        for surface in sorted(set(surfaces)):
            alive = sorted((t for t, track in enumerate(tracks)
                            if track[0] == surface and track[4] == i - 1),
                           key=lambda t: tracks[t][2][0])
            mine = sorted((k for k in np.flatnonzero(found[i]) if surfaces[k] == surface),
                          key=lambda k: values[i, k, _WHERE])

            def cost(a, b):
                _, _, last, before, _ = tracks[alive[a]]
                guesses = [last] if before is None else [last, 2.0 * last - before]
                return min(_distance(g, _key(values[i, mine[b]], depth[i, mine[b]]))
                           for g in guesses)

            pairs = _pair(alive, mine, cost, _TRACK_JUMP)
            for a, b in pairs:
                t, k = alive[a], mine[b]
                track = tracks[t]
                track[2], track[3], track[4] = _key(values[i, k], depth[i, k]), track[2], i
                owner[i, track[1]], out[i, track[1]] = t, values[i, k]
                held[i, track[1]] = depth[i, k]
            paired = {mine[b] for _, b in pairs}
            newcomers += [k for k in mine if k not in paired]
        for k in sorted(newcomers, key=lambda k: -depth[i, k]):  # deepest first
            surface = surfaces[k]
            free = [j for j in range(p) if surfaces[j] == surface
                    and owner[i, j] < 0 and (i == 0 or owner[i - 1, j] < 0)]
            if not free:
                # more patches than slots: the shallowest patch gives up its slot
                taken = [j for j in range(p) if surfaces[j] == surface and owner[i, j] >= 0]
                j = min(taken, key=lambda j: held[i, j]) if taken else None
                if j is None or held[i, j] >= depth[i, k]:
                    continue
                tracks[owner[i, j]][4] = -1  # that track ends here
                free = [j]
            tracks.append([surface, free[0], _key(values[i, k], depth[i, k]), None, i])
            owner[i, free[0]] = len(tracks) - 1
            out[i, free[0]] = values[i, k]
            held[i, free[0]] = depth[i, k]
    clear = np.zeros(values.shape[-1])
    clear[0] = -_CLEAR
    for j in range(p):
        have = np.flatnonzero(owner[:, j] >= 0)
        if have.size == 0:
            out[:, j] = clear
            continue
        for i in np.flatnonzero(owner[:, j] < 0):
            near = have[np.argmin(np.abs(have - i))]
            out[i, j] = out[near, j]
            fall = min(_CLEAR, _fall(held[:, j], owner[:, j], near, i) * abs(i - near))
            out[i, j, 0] += out[i, j, 1] * (heights[i] - heights[near]) - fall
    return out, owner >= 0


def _fall(held, owner, near, i):
    """How fast [m per node] a slot's depth falls from ``near``, the last node whose
    patch it held (``held``: the depths), toward ``i``: the patch's own trend over the
    node before ``near`` when the same patch was there (a continued line has no kink for
    the spline to ring at) between ``_RAMP_MIN`` and ``_RAMP``, and at least its depth at
    ``near`` (a gone patch is clear of the rail from the next node on)."""
    inner = near - 1 if i > near else near + 1
    trend = 0.0
    if 0 <= inner < len(held) and owner[inner] == owner[near]:
        trend = held[inner] - held[near]
    return max(float(np.clip(trend, _RAMP_MIN, _RAMP)), float(held[near]))


def _match(found, values, depth, reference, owned, surfaces, rigid, height, reference_height):
    """Values (P, F) of a node in the slots of an already assigned neighbour
    (``reference`` (P, F), ``owned`` (P,)): each surface's patches paired in order along
    the wheel with the neighbour's owned slots (:func:`_pair`, as many pairs as there
    can be, then the nearest), a newcomer to a free slot. A slot left empty keeps the
    neighbour's values: as they are when ``rigid`` (the next deeper approach level: its
    depth offset and slope continue the patch as the wheel rises), else with the
    neighbour's depth (the wheel's vertical position is ``height`` [m] here,
    ``reference_height`` there), clear of the rail by at least one ramp step
    (``_RAMP``) where the neighbour held a patch. Returns the values and the owned
    flags."""
    out, taken = reference.copy(), np.zeros(len(owned), dtype=bool)
    # the neighbour's depths: its patches' lines continued to this height when rigid
    reference_depth = reference[:, 0] - reference[:, 1] * (height if rigid else reference_height)
    for surface in sorted(set(surfaces)):
        slots = sorted((j for j in range(len(owned)) if surfaces[j] == surface and owned[j]),
                       key=lambda j: reference[j, _WHERE])
        mine = sorted((k for k in np.flatnonzero(found) if surfaces[k] == surface),
                      key=lambda k: values[k, _WHERE])

        def cost(a, b):
            j, k = slots[a], mine[b]
            return _distance(_key(reference[j], reference_depth[j]), _key(values[k], depth[k]))

        pairs = _pair(slots, mine, cost, _MATCH_LIMIT)
        for a, b in pairs:
            out[slots[a]], taken[slots[a]] = values[mine[b]], True
        paired = {mine[b] for _, b in pairs}
        free = [j for j in range(len(owned)) if surfaces[j] == surface and not owned[j]]
        for k in sorted((k for k in mine if k not in paired), key=lambda k: -depth[k]):
            if free:
                j = free.pop(0)
                out[j], taken[j] = values[k], True
    if not rigid:
        out[~taken, 0] += out[~taken, 1] * (height - reference_height)
        gone = ~taken & owned
        out[gone, 0] -= np.maximum(_RAMP, reference_depth[gone])
        return out, taken
    return out, owned | taken


def _assign_slots(found, values, depth, heights, surfaces):
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
            owned[(i,) + ref], surfaces, rigid, heights[i, j, k, m], heights[(i,) + ref])

    out[:, jc, kc, deep], owned[:, jc, kc, deep] = _track_line(
        found[:, jc, kc, deep], values[:, jc, kc, deep], depth[:, jc, kc, deep], surfaces,
        heights[:, jc, kc, deep])
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


def _limit_rates(values, heights):
    """``values`` (L, Y, R, A, P, F) with each geometry rate no larger than three times
    the field's change per metre of height to either neighbouring level (the
    Fritsch-Carlson bound: the Hermite interpolation between two levels then does not
    overshoot them; ``heights`` (L, Y, R, A) [m]). The search's rates are exact but
    unbounded where a patch is born (the centre of a vanishing interpenetration moves
    without limit) or its deepest point lies on a flat top; they bound the others only
    where the field is flat or turns between levels."""
    # how far the wheel comes down from each level to the next [m]
    drop = np.maximum(heights[..., :-1] - heights[..., 1:], 1e-12)[..., None, None]
    secant = np.abs(np.diff(values[..., _VALUES], axis=3)) / drop
    bound = np.full(secant.shape[:3] + (secant.shape[3] + 1,) + secant.shape[4:], np.inf)
    bound[..., :-1, :, :] = secant
    bound[..., 1:, :, :] = np.minimum(bound[..., 1:, :, :], secant)
    out = values.copy()
    out[..., _RATES] = np.clip(values[..., _RATES], -3.0 * bound, 3.0 * bound)
    return out


def _search_side(wheel, rail, rail_offset, config, grid, side, chunk, progress):
    """The search at every node of ``grid`` for the ``side`` rail, in compiled batches of
    ``chunk`` nodes: found (L, Y, R, A, P), values (L, Y, R, A, P, F), depth (L, Y, R,
    A, P), heights (L, Y, R, A) and the miss of each node [m] (:func:`_node`);
    ``progress(done)`` after each batch."""
    radius = float(wheel.nominal_radius)
    nodes = np.stack(np.meshgrid(grid.lateral.nodes, grid.yaw.nodes, grid.roll.nodes,
                                 indexing="ij"), axis=-1).reshape(-1, 3)
    parts = []
    for start in range(0, len(nodes), chunk):
        batch = nodes[start:start + chunk]
        padded = np.concatenate([batch, np.repeat(batch[-1:], chunk - len(batch), 0)])
        out = _run_nodes(wheel, rail, float(rail_offset), jnp.asarray(padded), jnp.asarray(side),
                         config, radius, grid.levels)
        parts.append([np.asarray(x)[:len(batch)] for x in out])
        if progress is not None:
            progress(start + len(batch))
    shape = (grid.lateral.count, grid.yaw.count, grid.roll.count)
    return tuple(np.concatenate(x).reshape(shape + np.shape(x[0])[1:]) for x in zip(*parts))


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
    count = grid.lateral.count * grid.yaw.count * grid.roll.count
    total, worst_miss, misses = 2 * count, 0.0, 0
    sides = []
    for n, side in enumerate((1.0, -1.0)):
        report = None if progress is None else (lambda done: progress(n * count + done, total))
        found, values, depth, heights, miss = _search_side(wheel, rail, rail_offset, config, grid,
                                                           side, chunk, report)
        worst_miss = max(worst_miss, float(np.max(miss)))
        misses += int(np.sum(miss > _LEVEL_TOLERANCE))
        tracked = _limit_rates(_assign_slots(found, values, depth, heights, surfaces)[..., :_WHERE],
                               heights)
        # the wheel's vertical position at each level as one more slot (first field)
        extra = np.zeros(heights.shape + (1, len(FIELDS)))
        extra[..., 0, 0] = heights
        sides.append(np.concatenate([tracked, extra], axis=-2))
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


def _pose_weights(table: ContactTable, side_index, lateral, yaw, roll):
    """Nodes (27,) of the 3 x 3 x 3 block of B-spline coefficients around a pose (row
    indices of ``table.heights``) and their weights (27,): the product of the quadratic
    B-spline weights along lateral, yaw and roll (C1)."""
    index = jnp.asarray(side_index, dtype=jnp.int32)
    weight = jnp.ones(())
    for axis, x, count in zip(_pose_axes(table.grid), (lateral, yaw, roll), table.shape[1:4]):
        start, w = _spline_weights(axis, x)
        offsets = jnp.arange(len(w), dtype=jnp.int32)
        index = (index * count)[..., None] + start + offsets
        weight = weight[..., None] * w
    return index.reshape(-1), weight.reshape(-1)


def _two_levels(heights, vertical):
    """The levels ``i, i + 1`` around the wheel's ``vertical`` position [m] (``heights``
    (A,) decreasing: the wheel lower at deeper levels; the first or last pair beyond
    them)."""
    i = jnp.clip(jnp.sum(heights > vertical) - 1, 0, heights.shape[0] - 2)
    return i + jnp.arange(2)


def _along_levels(heights, fields, vertical, levels):
    """Per slot the depth [m] and the geometry (:data:`GEOMETRY`) at the wheel's
    ``vertical`` position [m] from the two approach levels around it (``heights`` (2,),
    the wheel lower at the second; ``fields`` (2, P, F); their depths ``levels`` (2,)),
    by cubic Hermite interpolation in the vertical position (C1): the depth from each
    level's depth and slope (beyond the levels, the nearer level's line), the geometry
    from its values and rates (beyond the levels, the nearer level's values)."""
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
    geometry = (h00 * value[0] + h10 * span * rate[0] + h01 * value[1] + h11 * span * rate[1])
    return depth, geometry


def table_patches(table: ContactTable, wheel, rail, track, rail_offset, wheelset_position,
                  wheelset_rotation, side) -> ContactPatches:
    """Contact patches of one wheel from ``table`` instead of the search: the same
    :class:`ContactPatches` as :func:`jaxrail.contact.search_wheel` (leading shape
    ``(P,)``), each patch's penetration interpolated between the approach levels in the
    wheel's vertical position (:func:`_along_levels`)."""
    side = jnp.asarray(side, dtype=jnp.float64)
    (lateral, vertical, yaw, roll, s_rail, rail_origin, rail_axes, origin,
     frame) = relative_pose(track, rail_offset, table.radius, wheelset_position,
                            wheelset_rotation, side)
    side_index = jnp.where(side > 0.0, 0, 1).astype(jnp.int32)
    slots, count = len(table.surfaces), table.shape[4]
    nodes, weight = _pose_weights(table, side_index, lateral, yaw, roll)
    heights = weight @ table.heights[nodes]
    two = _two_levels(heights, vertical)
    block = table.rows[(nodes[:, None] * count + two).reshape(-1)].reshape(len(nodes), 2, -1)
    # (as an einsum over (node, level) with the weights broadcast: XLA:CPU runs the same
    # sum as a matrix product with the levels folded into the columns 2.4 times slower)
    weights = jnp.broadcast_to(weight[:, None], (len(nodes), 2))
    fields = jnp.einsum("nl,nlf->lf", weights, block).reshape(2, slots, len(FIELDS))
    depth, interpolated = _along_levels(heights[two], fields, vertical,
                                        jnp.asarray(table.grid.levels)[two])
    y_deepest, centre, breadth, rail_from_wheel, curvature = (
        interpolated[:, k] for k in range(len(GEOMETRY)))
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
                    **contact_geometry(surface, rail, wheel.nominal_radius, yw, yr, dx,
                                       rail_origin, rail_axes, side))

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
        y_track=side * (rail_offset + y_rail) + rail_displacement(track, s_rail, side)[0],
        curvature_contact_y=curvature,
        **geometry,
    )
