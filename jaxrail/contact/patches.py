"""Contact patches from per-strip depths, and sub-strip refinement.

A patch is a run of adjacent penetrating strips (DESIGN.md §4, step 3), or one of the
local depth maxima of a run that has several (conformal two-point contact, see
:func:`find_patches`). Its contact point is the strip of largest penetration, refined
below the strip spacing by a parabola through the neighbouring strips and Newton steps
on ``d depth / d y``, so that contact positions move continuously as the pose changes.
"""

import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

_NO_PATCH = -1.0e3  # depth placeholder outside a patch: finite, so gradients stay finite
NEWTON_STEPS = 2
CANDIDATE_DEPTH = 1.0e-4  # [m] local maxima this close to contact are refined


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
) -> tuple[Int[Array, " p"], Bool[Array, " p"], Float[Array, " p"]]:
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

    Arguments:
        depth: signed depth of each strip [m] (> 0 penetrating), strips in lateral order.
        max_patches: number of patch slots (static).
        candidate_depth: tolerance [m] on the parabola peak of a local maximum.

    Returns ``(index, found, keep)``: per slot the strip of one of the ``max_patches``
    deepest maxima (by depth after the cut; in lateral order, empty slots last),
    whether the slot holds one, and the fraction of its depth it keeps (multiply the
    refined depth by it; 1 for a maximum alone in its run).
    """
    n = depth.shape[0]
    parabola = _parabola_peak(depth)
    member = (depth > 0.0) | (parabola > -candidate_depth)
    inside = jnp.where(member, depth, _NO_PATCH)
    left = jnp.concatenate([jnp.full((1,), _NO_PATCH), inside[:-1]])
    right = jnp.concatenate([inside[1:], jnp.full((1,), _NO_PATCH)])
    is_peak = member & ((inside >= left) & (inside > right) | (inside > left) & (inside >= right))

    # Peaks ranked 1..m in lateral order; strips from peak r up to peak r + 1 have rank r.
    rank = jnp.cumsum(is_peak)
    count = rank[-1]
    peak_rank = jnp.where(is_peak, rank, 0)
    # Strip depths, not parabola peaks: the largest strip depth of a maximum is continuous
    # when the maximum moves from one strip to the next, the parabola's estimate is not.
    peak_depth = jax.ops.segment_max(jnp.where(is_peak, inside, _NO_PATCH), peak_rank, num_segments=n + 1)
    peak_index = jax.ops.segment_max(jnp.where(is_peak, jnp.arange(n), -1), peak_rank, num_segments=n + 1)
    saddle = jax.ops.segment_min(inside, rank, num_segments=n + 1)  # non-members break the run
    ranks = jnp.arange(n + 1)
    saddle = jnp.where((ranks >= 1) & (ranks < count), saddle, _NO_PATCH)  # saddle after peak r

    def cut_toward(s, own, other):
        excess_own, excess_other = own - s, other - s
        total = excess_own + excess_other
        shared = (s > 0.0) & (total > 0.0)
        return jnp.where(shared, s * excess_other / jnp.where(shared, total, 1.0), 0.0)

    next_depth = jnp.concatenate([peak_depth[1:], jnp.full((1,), _NO_PATCH)])
    previous_depth = jnp.concatenate([jnp.full((1,), _NO_PATCH), peak_depth[:-1]])
    previous_saddle = jnp.concatenate([jnp.full((1,), _NO_PATCH), saddle[:-1]])
    cut = jnp.maximum(cut_toward(saddle, peak_depth, next_depth),
                      cut_toward(previous_saddle, peak_depth, previous_depth))
    exists = (ranks >= 1) & (ranks <= count)
    score = jnp.where(exists, peak_depth - cut, 2.0 * _NO_PATCH)
    _, slots = jax.lax.top_k(score, max_patches)
    found = exists[slots]
    order = jnp.argsort(jnp.where(found, slots, slots + n + 1))  # lateral order, empty last
    slots, found = slots[order], found[order]
    # The fraction of its depth a maximum keeps: applied to the refined depth, it leaves
    # isolated maxima untouched and takes a maximum born from a shoulder from zero.
    shared = found & (cut[slots] > 0.0)
    keep = jnp.where(shared, 1.0 - cut[slots] / jnp.where(shared, peak_depth[slots], 1.0), 1.0)
    return jnp.maximum(peak_index[slots], 0), found, keep


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
    # through the strip geometry (which made compilation slow).
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
