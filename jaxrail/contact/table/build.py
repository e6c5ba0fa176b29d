"""Building a contact table: the paper's search at every node of the grid, each node's
wheel lowered to the approach levels, in compiled batches; the slots tracked
(:mod:`.slots`) and the spline coefficients prefiltered (:mod:`.spline`)."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ...track import Rails, rail_frame, straight_track
from ...track.rails import HALF_TAPING_DISTANCE
from ..search import SearchConfig, deepest_depth, search_wheel_parts
from ..strip import wheel_frame
from .grid import _WHERE, FIELDS, GEOMETRY, ContactTable, TableGrid
from .slots import _assign_slots, _limit_rates
from .spline import _prefilter

_CANDIDATE = 1.5e-4  # [m] a found slot deeper than -this is a patch (search: 1e-4)
_LEVEL_TOLERANCE = 1.0e-7  # [m] on the deepest depth at each approach level (reported)
FIRST_STEPS, NEXT_STEPS = 24, 10  # Newton steps to the first approach level, to each next


def _pose_on_straight(track, radius, lateral, vertical, yaw, roll, side):
    """Wheelset pose on a straight level ``track`` at s = 50 m whose ``side`` wheel has
    this relative pose."""
    rail_origin, rail_axes = rail_frame(track, 50.0, side)
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
    (profile ``rail`` at ``rail_offset`` [m], a float: a constant of the program) with
    the wheel lowered until its deepest patch penetrates each of the ``levels`` [m].

    Returns ``(found (L, P), values (L, P, len(FIELDS) + 1), depth (L, P), heights (L,),
    miss)``: the slots holding a patch, their fields and contact point (``_WHERE``),
    their signed depths, the wheel's
    vertical position [m] at each level, and the largest error [m] of the deepest depth
    against its level."""
    track = straight_track(100.0, rails=Rails(rail, rail_offset))
    first_strip = jnp.stack([config.strip_grid(surface)[0] for surface in wheel.surfaces])

    def pose(vertical):
        return _pose_on_straight(track, radius, lateral, vertical, yaw, roll, side)

    def residual(z, depth):
        return deepest_depth(wheel, track, *pose(z), side, config) - depth

    depths = jnp.asarray(levels)
    passes = _height_passes(len(levels))

    def one_pass(state, i):
        """One pass of the safeguarded Newton method on the vertical position for each
        level's depth (the deepest depth falls monotonically as the wheel rises): a
        level's first pass sets its bracket, each pass evaluates the depth once, its
        last one only records the position and the depth's residual [m] there."""
        z, lo, hi, heights, misses = state
        level, starts, closes = passes[0][i], passes[1][i], passes[2][i]
        depth = depths[level]
        # deeper: lower than the last level's position, by at most ten times the extra depth
        fresh = starts & (level > 0)
        lo = jnp.where(fresh, z - 10.0 * (depth - depths[jnp.maximum(level - 1, 0)]), lo)
        hi = jnp.where(fresh, z, hi)
        z = jnp.where(starts, 0.5 * (lo + hi), z)
        f, df = jax.jvp(lambda v: residual(v, depth), (z,), (jnp.ones_like(z),))
        lo_next, hi_next = jnp.where(f > 0.0, z, lo), jnp.where(f > 0.0, hi, z)
        newton = z - f / jnp.where(df < -1e-3, df, -1e-3)
        inside = (newton > lo_next) & (newton < hi_next)
        z_next = jnp.where(inside, newton, 0.5 * (lo_next + hi_next))
        record = closes & (jnp.arange(len(levels)) == level)
        return (jnp.where(closes, z, z_next), jnp.where(closes, lo, lo_next),
                jnp.where(closes, hi, hi_next), jnp.where(record, z, heights),
                jnp.where(record, f, misses)), None

    def slots(z):
        patches, parts = search_wheel_parts(wheel, track, *pose(z), side, config)
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

    zero, empty = jnp.zeros(()), jnp.zeros(len(levels))
    (_, _, _, heights, misses), _ = jax.lax.scan(
        one_pass, (zero, zero - 0.03, zero + 0.03, empty, empty), jnp.arange(len(passes[0])))
    heights = jax.lax.stop_gradient(heights)
    found, values = jax.vmap(level)(heights)
    depth = values[..., 0] - values[..., 1] * heights[:, None]
    return found, values, depth, heights, jnp.max(jnp.abs(misses))


def _height_passes(count):
    """The passes of :func:`_node`'s height solve for ``count`` levels: each pass's
    level, whether it starts the level and whether it closes it (int32, bool, bool
    arrays). The first level takes ``FIRST_STEPS`` Newton steps from (-3 cm, 3 cm), each
    further one ``NEXT_STEPS`` from the last level's position, then one closing pass."""
    steps = [FIRST_STEPS] + [NEXT_STEPS] * (count - 1)
    level = np.concatenate([np.full(n + 1, k) for k, n in enumerate(steps)])
    first = np.concatenate([[0], np.cumsum([n + 1 for n in steps])[:-1]])
    starts = np.isin(np.arange(len(level)), first)
    closes = np.isin(np.arange(len(level)), first + np.asarray(steps))
    return jnp.asarray(level, jnp.int32), jnp.asarray(starts), jnp.asarray(closes)


# The build runs each node's search at every approach level, thousands of nodes: its
# program is compiled at XLA's full optimisation (its defaults) even where XLA_FLAGS
# asks for cheaper compiles, as the test suite does. Building the suite's 1:40 test grid
# took 57 s at level 0 and 35 s at these, the compile the same (22-24 s).
_FULL_OPTIMISATION = {"xla_backend_optimization_level": 3,
                      "xla_llvm_disable_expensive_passes": False}


@eqx.filter_jit(compiler_options=_FULL_OPTIMISATION)
def _run_nodes(wheel, rail, rail_offset, nodes, side, config, radius, levels):
    """:func:`_node` vmapped over ``nodes`` (N, 3) (one compilation for both sides and
    every chunk)."""
    return jax.vmap(lambda x: _node(wheel, rail, rail_offset, x[0], x[1], x[2], side, config,
                                    radius, levels))(nodes)


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


def build_contact_table(wheel, rails: Rails, config: SearchConfig = SearchConfig(),
                        grid: TableGrid = TableGrid(), chunk: int = 256,
                        progress=None) -> tuple[ContactTable, dict]:
    """Run the paper's search at every node of ``grid`` for both rails of ``rails``
    (:class:`jaxrail.track.Rails`), on a straight track.

    Returns the table and diagnostics: ``nodes``, and ``level_misses``, the nodes where
    the deepest depth could not be brought within 0.1 um of an approach level (the
    refined depth of the search jumps in a few poses where the contact moves across the
    S1002 throat), with the largest miss ``worst_level_miss_m``; such a node keeps the
    search's data at the height reached.

    Arguments:
        wheel, config: as :func:`jaxrail.contact.search_wheel`.
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
        found, values, depth, heights, miss = _search_side(wheel, rails.profile, rails.offset,
                                                           config, grid, side, chunk, report)
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
