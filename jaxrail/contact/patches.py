"""Contact patches from per-strip depths, and sub-strip refinement.

A patch is a run of adjacent penetrating strips (docs/design.md §4, step 3), or one of the
local depth maxima of a run that has several (conformal two-point contact, see
:func:`find_patches`). Its depth is that of the strip of largest penetration, refined
below the strip spacing by a parabola through the neighbouring strips and Newton steps
on ``d depth / d y``. Its contact point is that deepest point for a narrow patch and the
centre of its interpenetration for a wide one (:func:`overlap_centre`), so that contact
positions move continuously as the pose changes, also in conformal contact.
"""

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

_NO_PATCH = -1.0e3  # depth placeholder outside a patch: finite, so gradients stay finite
NEWTON_STEPS = 2
CANDIDATE_DEPTH = 1.0e-4  # [m] local maxima this close to contact are refined
ARGMAX_SLACK = 1.0e-9  # entries this close (relative) to the largest count as largest


def _parabola_peak(depth):
    """Peak of the parabola through each strip and its neighbours, where the strip is a
    local maximum (else -inf-like): finds patches narrower than the strip spacing."""
    d_minus = jnp.concatenate([depth[:1], depth[:-1]])
    d_plus = jnp.concatenate([depth[1:], depth[-1:]])
    local_max = (depth >= d_minus) & (depth > d_plus) | (depth > d_minus) & (depth >= d_plus)
    bend = 2.0 * depth - d_minus - d_plus
    safe_bend = jnp.where(bend > 0.0, bend, 1.0)
    peak = depth + jnp.where(bend > 0.0, (d_minus - d_plus) ** 2 / (8.0 * safe_bend), 0.0)
    return jnp.where(local_max, peak, _NO_PATCH)


def find_patches(
    depth: Float[Array, " n"], max_patches: int, candidate_depth: float = CANDIDATE_DEPTH,
) -> tuple[Int[Array, " p"], Bool[Array, " p"], Float[Array, " p"], Float[Array, "p n"]]:
    """Local depth maxima of the (nearly) penetrating strips as patches, deepest first.

    A strip is a member when its depth is positive, or when it is a local maximum whose
    parabola through its neighbours peaks above ``-candidate_depth``: a patch narrower
    than the strip spacing (contact onset, the steep flange) is then still found, and
    the caller decides from the refined depth whether it is in contact. Every strip can
    be a member, also one whose rail foot lies beyond the rail domain: its depth is
    measured to the rail continued along its end tangent (the gauge face, 86 degrees at
    the UIC60 1:40 gauge-side end), which is continuous, whereas a gate on "foot inside
    the domain" would change a patch reaching the domain end by a whole strip of depth.

    Every local maximum of the depth over the members is a patch. Two maxima in one run
    of members (conformal two-point contact: S1002 tread and flange root on UIC60 near
    5 mm, centred near 0 mm) share the interpenetration below the saddle between them:
    the maximum of strip depth ``d_i`` next to the saddle ``s > 0`` and the maximum
    ``d_j`` across it gives up ``c_i = s (d_j - s) / ((d_i - s) + (d_j - s))`` (the larger
    of the two where it has saddles on both sides) and keeps the fraction
    ``1 - c_i / d_i`` of its depth. The two cuts add up to the saddle; they are symmetric,
    vanish when the run splits (``s = 0``), and a maximum just born from a shoulder
    (``d_i = s``) keeps nothing, so patches appear, merge and hand over load
    continuously instead of the contact point jumping between the two regions.

    The interpenetration of every strip is shared out among the maxima the same way
    (the ``weights``): a strip belongs to the basin of the maximum on its side of the
    saddle; the part of its depth above the basin's higher saddle ``S`` goes to that
    maximum, the part below ``S`` is split with the maximum across it in the proportion
    ``(S - c) / S`` each keeps of the shared layer. The weights of all maxima add up to
    the positive depth of each strip, and they change continuously through the birth of
    a maximum and the splitting of a run (the layer that changes hands is then empty).

    Arguments:
        depth: signed depth of each strip [m] (> 0 penetrating), strips in lateral order.
        max_patches: number of patch slots (static).
        candidate_depth: tolerance [m] on the parabola peak of a local maximum.

    Returns ``(index, found, keep, weights)``: per slot the strip of one of the
    ``max_patches`` deepest maxima (by depth after the cut; in lateral order, empty
    slots last), whether the slot holds one, the fraction of its depth it keeps
    (multiply the refined depth by it; 1 for a maximum alone in its run), and the
    share [m] of each strip's interpenetration that belongs to it (shape
    ``(max_patches, n)``, zero for empty slots).
    """
    n = depth.shape[0]
    parabola = _parabola_peak(depth)
    member = (depth > 0.0) | (parabola > -candidate_depth)
    inside = jnp.where(member, depth, _NO_PATCH)
    left = jnp.concatenate([jnp.full((1,), _NO_PATCH), inside[:-1]])
    right = jnp.concatenate([inside[1:], jnp.full((1,), _NO_PATCH)])
    is_peak = member & ((inside >= left) & (inside > right) | (inside > left) & (inside >= right))
    runs = _Runs.of(inside, is_peak)

    # Per peak (at its strip): the saddles to the previous and the next peak of its run
    # (NO_PATCH where there is none, or where a non-member breaks the run), and the cut.
    # Strip depths, not parabola peaks: the largest strip depth of a maximum is continuous
    # when the maximum moves from one strip to the next, the parabola's estimate is not.
    cut_right = _cut_toward(runs.right_saddle, inside, runs.following_depth)
    cut_left = _cut_toward(runs.left_saddle, inside, runs.preceding_depth)
    cut = jnp.maximum(cut_right, cut_left)
    score = jnp.where(is_peak, inside - cut, 2.0 * _NO_PATCH)
    chosen = _top_indices(score, max_patches)
    found = is_peak[chosen]
    chosen, found = _lateral_order(chosen, found, n)
    # The fraction of its depth a maximum keeps: applied to the refined depth, it leaves
    # isolated maxima untouched and takes a maximum born from a shoulder from zero.
    shared = found & (cut[chosen] > 0.0)
    keep = jnp.where(shared, 1.0 - cut[chosen] / jnp.where(shared, inside[chosen], 1.0), 1.0)
    weights = _strip_shares(depth, inside, runs, cut_left, cut_right, chosen, found)
    return jnp.where(found, chosen, 0), found, keep, weights


def _cut_toward(s, own, other):
    """The depth [m] a maximum ``own`` gives up to the maximum ``other`` across the saddle
    ``s`` (:func:`find_patches`); zero where the saddle is not above the rail."""
    excess_own, excess_other = own - s, other - s
    total = excess_own + excess_other
    shared = (s > 0.0) & (total > 0.0)
    return jnp.where(shared, s * excess_other / jnp.where(shared, total, 1.0), 0.0)


class _Runs(NamedTuple):
    """The peaks of a row of strips, each strip's place between them, and the saddles
    (member depths ``inside`` (n,), non-members at ``_NO_PATCH``). Strip indices are
    int32; ``-1`` stands for no peak before, ``n`` for none after.

    Each strip belongs to the segment of the last peak at or before it (strips before
    the first peak to a segment of their own); a peak's saddle toward the next peak is
    the smallest depth of its segment, toward the previous one that of the previous
    segment. Computed with cumulative maxima and minima, one segmented minimum (an
    associative scan) and two gathers, each of several rows at once: no scatter and
    no sort, so that a loop holding the search compiles into one kernel
    (:mod:`jaxrail.compilation.loop_kernels`)."""

    preceding_at: jax.Array  # (n,) the last peak at or before each strip
    following: jax.Array  # (n,) the first peak after each strip
    preceding: jax.Array  # (n,) the last peak before each strip
    left_saddle: jax.Array  # (n,) [m] at a peak: its saddle toward the previous peak
    right_saddle: jax.Array  # (n,) [m] at a peak: its saddle toward the next peak
    following_depth: jax.Array  # (n,) [m] the member depth of the following peak (or _NO_PATCH)
    preceding_depth: jax.Array  # (n,) [m] the member depth of the preceding peak (or _NO_PATCH)
    past_saddle: jax.Array  # (n,) bool: a strip at its segment's smallest depth lies before it

    @classmethod
    def of(cls, inside, is_peak):
        """The runs of a row: member depths ``inside`` (n,) [m], ``is_peak`` (n,) bool."""
        n = inside.shape[0]
        strips = jnp.arange(n, dtype=jnp.int32)
        preceding_at = jax.lax.cummax(jnp.where(is_peak, strips, -1))
        following_at = jax.lax.cummin(jnp.where(is_peak, strips, n), reverse=True)
        following = jnp.concatenate([following_at[1:], jnp.full((1,), n, jnp.int32)])
        preceding = jnp.concatenate([jnp.full((1,), -1, jnp.int32), preceding_at[:-1]])
        _, lowest = jax.lax.associative_scan(_segmented_min, (is_peak, inside))
        lowest_before = _shifted(lowest)  # the running minimum up to the strip before
        # a peak's segment ends before the next peak; the last one has no saddle after it
        has_following, has_preceding = following < n, preceding >= 0
        lowest_ending, following_depth = _rows_at(following, lowest_before, inside)
        right_saddle = jnp.where(has_following, lowest_ending, _NO_PATCH)
        left_saddle = jnp.where(has_preceding, lowest_before, _NO_PATCH)
        preceding_saddle, preceding_depth = _rows_at(preceding, right_saddle, inside)
        # the saddle each strip's segment ends at (none before the first peak)
        saddle = jnp.where(is_peak, right_saddle,
                           jnp.where(has_preceding, preceding_saddle, _NO_PATCH))
        return cls(preceding_at, following, preceding, left_saddle, right_saddle,
                   jnp.where(has_following, following_depth, _NO_PATCH),
                   jnp.where(has_preceding, preceding_depth, _NO_PATCH),
                   ~is_peak & (lowest_before == saddle))

    def basin(self):
        """(n,) the peak whose basin each strip is in: its segment's peak up to the first
        strip at the segment's smallest depth, the next peak after it; strips before the
        first peak belong to it, those after the last peak's saddle to the last peak
        (n where there is no peak)."""
        n = self.following.shape[0]
        in_segment = jnp.where(self.past_saddle & (self.following < n), self.following,
                               self.preceding_at)
        return jnp.where(self.preceding_at < 0, self.following, in_segment)


def _shifted(values):
    """``values`` (n,) moved one strip on: each strip gets its predecessor's (the first
    its own)."""
    return jnp.concatenate([values[:1], values[:-1]])


def _rows_at(index, *rows):
    """Each of ``rows`` (n,) at the strips ``index`` (n,) (clipped to the row), in one
    gather of all of them."""
    n = index.shape[0]
    table = jnp.stack(rows, axis=-1)
    return tuple(table[jnp.clip(index, 0, n - 1)].T)


def _segmented_min(a, b):
    """Combine of a segmented running minimum: segments start where the flag is set."""
    starts_a, lowest_a = a
    starts_b, lowest_b = b
    return starts_a | starts_b, jnp.where(starts_b, lowest_b, jnp.minimum(lowest_a, lowest_b))


def _lateral_order(chosen, found, n):
    """``chosen`` strips and ``found`` flags (k,) reordered: found slots in lateral order,
    empty ones after them (by a count of smaller keys: no sort)."""
    key = jnp.where(found, chosen, chosen + n)
    position = jnp.sum(key[None, :] < key[:, None], axis=1)
    into = position[None, :] == jnp.arange(key.shape[0])[:, None]  # (slot, chosen)
    return (jnp.sum(jnp.where(into, chosen[None, :], 0), axis=1),
            jnp.any(into & found[None, :], axis=1))


def first_argmax(values, axis: int = -1):
    """``jnp.argmax`` up to rounding: the index (int32) of the first entry along ``axis``
    within ``ARGMAX_SLACK`` (relative) of the largest, by a maximum and then a minimum
    over the indices reaching it, two plain reductions (XLA:CPU runs argmax's reduction
    of pairs, compiled into a loop, several times slower). The slack because XLA may
    compute a fused producer of ``values`` again in each reduction, rounded differently
    (its CPU code generation contracts a multiplication and an addition into one where
    it can), so that no entry would equal the maximum. Where the maximum is NaN, the
    last index."""
    n = values.shape[axis]
    top = jnp.max(values, axis=axis, keepdims=True)
    slack = jnp.where(jnp.isfinite(top), ARGMAX_SLACK * jnp.abs(top), 0.0)
    positions = jax.lax.broadcasted_iota(jnp.int32, values.shape, axis % values.ndim)
    first = jnp.min(jnp.where(values >= top - slack, positions, n - 1), axis=axis)
    return first.astype(jnp.int32)


def _top_indices(score, k: int):
    """Indices of the ``k`` largest entries of ``score``, largest first, the lower index
    first among equal ones: ``lax.top_k``'s, by ``k`` arg-maxima (on the CPU ``top_k``
    of a short row costs ten times as much)."""
    positions = jnp.arange(score.shape[0])
    chosen = []
    for _ in range(k):
        best = first_argmax(score)
        chosen.append(best)
        score = jnp.where(positions == best, -jnp.inf, score)
    return jnp.stack(chosen).astype(jnp.int32)


def _strip_shares(depth, inside, runs, cut_left, cut_right, chosen, found):
    """Each slot's share [m] of every strip's positive depth (see :func:`find_patches`);
    ``chosen``: each slot's peak strip."""
    n = depth.shape[0]
    basin = runs.basin()
    # the basin's peak's saddles, cuts and neighbours, in one gather (n: no peak at all)
    saddle_left, saddle_right, basin_cut_left, basin_cut_right, following, preceding = _rows_at(
        basin, runs.left_saddle, runs.right_saddle, cut_left, cut_right,
        runs.following.astype(depth.dtype), runs.preceding.astype(depth.dtype))
    level_left = jnp.maximum(saddle_left, 0.0)  # before the basin's peak
    level_right = jnp.maximum(saddle_right, 0.0)  # after it
    toward_right = level_right >= level_left
    level = jnp.where(toward_right, level_right, level_left)
    cut = jnp.where(toward_right, basin_cut_right, basin_cut_left)
    neighbour = jnp.where(toward_right, following, preceding)
    kept = jnp.where(level > 0.0, (level - cut) / jnp.where(level > 0.0, level, 1.0), 1.0)

    positive = jnp.maximum(depth, 0.0)
    above = jnp.maximum(positive - level, 0.0)
    below = positive - above  # min(depth, level), the layer shared across the saddle
    own = above + kept * below
    given = (1.0 - kept) * below

    def share(slot):
        return (jnp.where(basin == slot, own, 0.0)
                + jnp.where(neighbour == slot.astype(depth.dtype), given, 0.0))

    return jnp.where(found[:, None], jax.vmap(share)(chosen), 0.0)


# A patch whose interpenetration is narrower than WIDE_FROM (its breadth: area over
# largest depth, 4/3 of the half-width for a parabolic gap) is located at its refined
# deepest point, one wider than WIDE_FULL at the centre of its interpenetration, with a
# linear blend between [m]. At the default 1 mm strip spacing the centre is taken only
# where at least three strips resolve the patch.
WIDE_FROM, WIDE_FULL = 3.0e-3, 6.0e-3


def _segment_coefficients(depth, y_grid):
    """What a unit weight at the start and at the end of each segment between strips
    adds to the zeroth, first and second moments about ``y = 0`` of a density that is
    linear between strips (:func:`_segment_moments`): two tuples of three (n - 1,) rows.

    Where the signed ``depth`` changes sign between two strips, the density falls to
    zero at the crossing of the linear interpolant, so the moments change continuously
    as a patch edge passes a strip. A segment of length L from ``a`` to ``b`` (densities
    at its ends) with middle ``c`` has moments ``L (a + b) / 2``, ``L^2 (b - a) / 12 +
    c M0`` and ``L^3 (a + b) / 24 + c (2 M1' + c M0)`` (``M1'`` its own first moment
    about ``c``), linear in ``a`` and ``b``: their coefficients. Rows, not one stacked
    array: XLA fuses a stack's producers into it and computes them once per row."""
    x0, x1 = y_grid[:-1], y_grid[1:]
    d0, d1 = depth[:-1], depth[1:]
    in0, in1 = d0 > 0.0, d1 > 0.0
    fall = jnp.where(in0 & ~in1, d0 / jnp.where(in0 & ~in1, d0 - d1, 1.0), 1.0)  # share of the segment
    rise = jnp.where(in1 & ~in0, d1 / jnp.where(in1 & ~in0, d1 - d0, 1.0), 1.0)
    start = jnp.where(in1 & ~in0, x1 - rise * (x1 - x0), x0)
    end = jnp.where(in0 & ~in1, x0 + fall * (x1 - x0), x1)
    length = jnp.where(in0 | in1, end - start, 0.0)
    middle = 0.5 * (start + end)
    half, twelfth = 0.5 * length, length**2 / 12.0
    first = middle * half  # the middle's share of the first moment
    third = length**3 / 24.0 + middle * first
    at_start = (half, first - twelfth, third - 2.0 * middle * twelfth)
    at_end = (half, first + twelfth, third + 2.0 * middle * twelfth)
    return (tuple(jnp.where(in0, c, 0.0) for c in at_start),
            tuple(jnp.where(in1, c, 0.0) for c in at_end))


def _segment_moments(weights, depth, y_grid, origin):
    """Zeroth, first and second moments of each patch's weight density about its
    ``origin`` [m]: ``weights`` (..., n) and ``origin`` (...) for any number of patches
    over the same strips.

    Products of the weights at the segments' starts and ends with their coefficients
    (:func:`_segment_coefficients`): a product's operands are computed once, where sums
    over strips would each repeat the weights and the segments' geometry (XLA fuses
    such cheap producers into every consumer). The moments about ``y = 0`` are then
    moved to the origin, which costs the second moment about the centre
    ``log10(y^2 / variance)`` of its 16 digits: 4 for a patch 3 mm wide (``WIDE_FROM``,
    below which the centre is not used) 70 mm from the taping line."""
    at_start, at_end = _segment_coefficients(depth, y_grid)
    m0, m1, m2 = (weights[..., :-1] @ s + weights[..., 1:] @ e for s, e in zip(at_start, at_end))
    origin = jnp.asarray(origin)
    return m0, m1 - origin * m0, m2 - origin * (2.0 * m1 - origin * m0)


def wide_point(y_deepest, centre, breadth):
    """Contact point [m] of a patch and its blend factor: its deepest point
    ``y_deepest`` [m] if it is narrower than ``WIDE_FROM``, the centre of its
    interpenetration ``centre`` [m] if wider than ``WIDE_FULL``, blended linearly in
    its ``breadth`` [m] between."""
    blend = jnp.clip((breadth - WIDE_FROM) / (WIDE_FULL - WIDE_FROM), 0.0, 1.0)
    return y_deepest + blend * (centre - y_deepest), blend


def overlap_density(weights: Float[Array, "... n"], depth: Float[Array, " n"],
                    y_grid: Float[Array, " n"], y_deepest):
    """Centre, breadth and overlap curvature of a patch's share of the interpenetration.

    Arguments as :func:`overlap_centre`, or ``weights`` (k, n) and ``y_deepest`` (k,) for
    k patches at once. Returns ``(centre, breadth, curvature)``: the
    lateral coordinate of the centroid of the weight density [m] (``y_deepest`` where
    the patch has no weight), its area over its largest value [m], and the relative
    lateral curvature [1/m] a parabolic gap would need to overlap as widely,
    ``2 delta / w^2`` with the half-width ``w^2 = 5 variance`` of the density and
    ``delta`` its largest value.
    """
    m0, m1, m2 = _segment_moments(weights, depth, y_grid, y_deepest)
    # the largest weight by its index, not jnp.max: max's derivative divides by the count
    # of entries equal to it, which XLA can make zero by computing the two differently
    peak = jnp.take_along_axis(weights, first_argmax(weights)[..., None], axis=-1)[..., 0]
    some = (m0 > 0.0) & (peak > 0.0)
    safe_m0 = jnp.where(some, m0, 1.0)
    breadth = jnp.where(some, m0 / jnp.where(some, peak, 1.0), 0.0)
    offset = m1 / safe_m0
    variance = m2 / safe_m0 - offset**2
    spread = some & (variance > 0.0)
    curvature = jnp.where(spread, 0.4 * peak / jnp.where(spread, variance, 1.0), 0.0)
    return y_deepest + offset, breadth, curvature


def overlap_centre(weights: Float[Array, " n"], depth: Float[Array, " n"], y_grid: Float[Array, " n"],
                   y_deepest):
    """Contact point and overlap curvature of a patch from its strip weights.

    A wide interpenetration (conformal contact: the S1002 throat against the UIC60 gauge
    corner overlaps over 8-10 mm at 0.1 mm depth) has a nearly flat top, and its deepest
    point moves by millimetres, with the contact angle by tens of degrees, for a change of
    pose of micrometres. Its centre (the centroid of the patch's share of the
    interpenetration, as in the Kik-Piotrowski method) moves smoothly. Narrow patches,
    which the strips resolve badly, keep their refined deepest point ``y_deepest``.

    Arguments:
        weights: the patch's share of each strip's depth [m] (:func:`find_patches`).
        depth: signed depth of each strip [m]; y_grid: strip coordinates [m].
        y_deepest: refined deepest point of the patch [m].

    Returns ``(y, blend, curvature)``: the lateral coordinate of the contact point [m]
    and the blend factor (:func:`wide_point`), and the overlap curvature [1/m]
    (:func:`overlap_density`).
    """
    centre, breadth, curvature = overlap_density(weights, depth, y_grid, y_deepest)
    return *wide_point(y_deepest, centre, breadth), curvature


SECANT_SPAN = 1.0e-3  # [m] half-span (arc length) of the secant curvature of a narrow patch


def secant_curvature(depth_fn, y, domain, span: float = SECANT_SPAN):
    """Relative lateral curvature of the gap near ``y`` [1/m along the wheel coordinate],
    ``-d''`` from the depth at three points ``span`` apart around ``y``, the stencil
    shifted (and, on a surface narrower than ``2 span``, shrunk) to stay in ``domain``.

    For a narrow patch this stands in for the sum of the two profile curvatures at one
    point. The UIC60 head is made of arcs (R300, R80, R13) whose curvatures jump at the
    junctions, so that sum changes the Hertz stiffness by up to a factor 2.5 as a contact
    point crosses one. The depth is continuously differentiable there, and its second
    difference over the span changes continuously, spreading the jump over 2 ``span``."""
    points, span = secant_stencil(y, domain, span)
    return stencil_curvature(jax.vmap(depth_fn)(points), span)


def secant_stencil(y, domain, span: float = SECANT_SPAN):
    """The three points [m] (3,) of :func:`secant_curvature` and the span [m] it uses
    (shrunk on a narrow surface)."""
    half_width = 0.5 * (domain[1] - domain[0])
    span = jnp.minimum(span, 0.5 * half_width)
    centre = jnp.clip(y, domain[0] + span, domain[1] - span)
    return centre + span * jnp.array([-1.0, 0.0, 1.0]), span


def stencil_curvature(depths, span):
    """:func:`secant_curvature` from the depths [m] (3,) at :func:`secant_stencil`'s
    points."""
    d_below, d_mid, d_above = depths
    return -(d_above - 2.0 * d_mid + d_below) / span**2


def refine_maximum(depth_fn, y_grid: Float[Array, " n"], depth: Float[Array, " n"], index, domain):
    """Refine the maximum of ``depth_fn`` near strip ``index`` below the strip spacing.

    A parabola through the strip and its neighbours gives the first estimate (within one
    spacing of it); ``NEWTON_STEPS`` Newton steps on ``d depth / d y`` follow (derivatives from
    a parabola on a spacing 20 times finer), each limited to half a spacing and skipped
    where the depth is not concave.
    Returns the refined lateral coordinate [m] inside ``domain``.
    """
    n = y_grid.shape[0]
    spacing = y_grid[1] - y_grid[0]
    d_minus = depth[jnp.maximum(index - 1, 0)]
    d_zero = depth[index]
    d_plus = depth[jnp.minimum(index + 1, n - 1)]
    interior = (index > 0) & (index < n - 1)
    bend = d_minus - 2.0 * d_zero + d_plus
    concave = interior & (bend < 0.0)
    safe_bend = jnp.where(concave, bend, -1.0)
    offset = jnp.where(concave, jnp.clip(0.5 * (d_minus - d_plus) / safe_bend, -1.0, 1.0), 0.0)
    y = y_grid[index] + offset * spacing

    # Newton steps from central-difference parabolas on a much finer spacing: the same
    # steps as Newton with exact derivatives up to O(probe^2), without nesting autodiff
    # through the strip geometry (which is slow to compile).
    probe = 0.05 * spacing

    def newton(y, _):
        d_left, d_mid, d_right = jax.vmap(depth_fn)(y + probe * jnp.array([-1.0, 0.0, 1.0]))
        curvature = d_left - 2.0 * d_mid + d_right
        concave = curvature < 0.0
        step = 0.5 * probe * (d_left - d_right) / jnp.where(concave, curvature, -1.0)
        step = jnp.where(concave, jnp.clip(step, -0.5 * spacing, 0.5 * spacing), 0.0)
        return jnp.clip(y + step, domain[0], domain[1]), None

    y, _ = jax.lax.scan(newton, y, None, length=NEWTON_STEPS)
    return y
