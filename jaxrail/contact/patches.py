"""Contact patches from per-strip depths, and sub-strip refinement.

A patch is a run of adjacent penetrating strips (DESIGN.md §4, step 3). Its contact
point is the strip of largest penetration, refined below the strip spacing by a
parabola through the neighbouring strips and one Newton step on ``d depth / d y``, so
that contact positions move continuously as the pose changes.
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
    depth: Float[Array, " n"], valid: Bool[Array, " n"], max_patches: int,
    candidate_depth: float = CANDIDATE_DEPTH,
) -> tuple[Int[Array, " p"], Bool[Array, " p"], Int[Array, ""]]:
    """Deepest strip of each run of (nearly) penetrating strips, deepest runs first.

    A strip belongs to a run when its depth is positive, or when it is a local maximum
    whose parabola through its neighbours peaks above ``-candidate_depth``: a patch
    narrower than the strip spacing (contact onset, the steep flange) is then still
    found, and the caller decides from the refined depth whether it is in contact.

    Arguments:
        depth: signed depth of each strip [m] (> 0 penetrating), strips in lateral order.
        valid: strips whose depth is meaningful (rail foot inside the rail domain).
        max_patches: number of patch slots (static).
        candidate_depth: tolerance [m] on the parabola peak of a local maximum.

    Returns ``(index, found, n_runs)``: per slot the deepest strip of one of the
    ``max_patches`` deepest runs (in lateral order, empty slots last), whether the slot
    holds a run, and
    the number of runs found (runs beyond ``max_patches`` are dropped).
    """
    # Neighbours outside the rail domain still give a continuous depth (to the tangent
    # at the domain end), good enough for the parabola; only the peak must be valid.
    peak = _parabola_peak(depth)
    member = valid & ((depth > 0.0) | (peak > -candidate_depth))
    depth = jnp.where(valid, jnp.maximum(depth, peak), _NO_PATCH)
    previous = jnp.concatenate([jnp.zeros((1,), bool), member[:-1]])
    run = jnp.cumsum(member & ~previous) * member
    n = depth.shape[0]
    run_depth = jax.ops.segment_max(jnp.where(member, depth, _NO_PATCH), run, num_segments=n + 1)
    run_depth = run_depth.at[0].set(2.0 * _NO_PATCH)
    _, labels = jax.lax.top_k(run_depth, max_patches)
    found = run_depth[labels] > _NO_PATCH
    # Runs in lateral order, empty slots last.
    order = jnp.argsort(jnp.where(found, labels, labels + n + 1))
    labels, found = labels[order], found[order]
    slots = labels[:, None] == run[None, :]
    index = jnp.argmax(jnp.where(slots, depth[None, :], _NO_PATCH), axis=1)
    return index, found, jnp.max(run)


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
