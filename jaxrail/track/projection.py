"""Projection of a point onto the track: arc length and track coordinates (eqs. 3-5).

The paper finds the rail cross-section nearest a wheel by requiring the distance
vector to be normal to the rail tangent, ``d . t = 0`` (eq. 5). For the centreline:
find ``s`` with ``g(s) = (p - c(s)) . t(s) = 0``, ``c`` the centreline and ``t`` the
(horizontal) tangent. Since ``dc/ds = t`` and ``dt/ds = kappa n0`` (``n0`` the
horizontal left normal), ``g'(s) = -1 + kappa (p - c) . n0``, exact on every segment
kind, so Newton converges quadratically.

Initial guess: ``s_guess`` if given (in a simulation, the vehicle's last arc length),
else the nearest of the track's coarse centreline samples (horizontal distance).
Then a fixed number of Newton steps without gradient, and one final Newton step with
gradient: at the converged root this step carries exactly the implicit-function
derivative ``ds = -(dg) / g'``, i.e. ``ds/dp = t / (1 - kappa * lateral)``, also with
respect to the track's parameters.

Valid for points within a few metres of the centreline (lateral well below the
curve radius), including beyond the ends (the end segments extended, see
:mod:`jaxrail.track.geometry`). The track is planar, so the vertical coordinate of
the point does not affect ``s``. From the nearest coarse sample Newton needs about
two steps to reach 1e-12 m on railway layouts; the default is two, and the final
step makes three (on the paper's curve, 20 000 points up to 1.5 m from the
centreline and 20 m beyond its ends, within 1.2e-13 m of the arc length they were
placed at: docs/track.md). Where the
layout comes back within a few samples' spacing of itself (loops, crossings) the
nearest sample can belong to the wrong branch: pass ``s_guess`` there.
"""

from typing import TYPE_CHECKING

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .geometry import (_cant_cos_sin, _from_sample, centreline_and_frame, curvature,
                       frame_from_cos_sin)

if TYPE_CHECKING:  # layout imports the rails, which project onto the track
    from .layout import Track


def _newton_update(s, d, tangent, kappa):
    """One Newton step on ``g(s) = d . t`` from ``s`` [m]: ``d`` (2,) [m] the point from
    the centreline at ``s``, ``tangent`` ``(cos h, sin h)`` and ``kappa`` [1/m] there."""
    ch, sh = tangent
    g = d[0] * ch + d[1] * sh
    dg = -1.0 + kappa * (-d[0] * sh + d[1] * ch)
    # g' ~ -1 for points near the track; the cap only guards points near the centre
    # of curvature (|kappa * lateral| -> 1), far outside the intended domain.
    dg = jnp.minimum(dg, -0.1)
    return s - g / dg


def _newton_step(track: "Track", point, s):
    centre, tangent = _from_sample(track, s)
    return _newton_update(s, point[:2] - centre[:2], tangent, curvature(track, s))


def _last_step(track: "Track", point, s):
    """The last Newton step from ``s`` [m] with the centreline there carried along:
    ``(s_new, centreline point (3,), (cos h, sin h))`` at ``s_new``, the point and
    tangent at ``s`` moved by the step to first order. After :func:`project`'s default
    two steps the last is far under 1e-6 m, so the second-order terms (``kappa step^2 /
    2``) are below rounding (``tests/track/test_projection.py``: within 2e-13 m of a new
    evaluation); the first-order term carries the derivative of ``s_new``."""
    centre, (ch, sh) = _from_sample(track, s)
    kappa = curvature(track, s)
    s_new = _newton_update(s, point[:2] - centre[:2], (ch, sh), kappa)
    step = s_new - s
    turn = kappa * step
    moved = centre + step * jnp.stack([ch, sh, jnp.zeros_like(ch)])
    return s_new, moved, (ch - sh * turn, sh + ch * turn)


def _nearest_sample(track: "Track", point):
    """Index of the coarse sample nearest ``point`` (horizontal distance)."""
    return jnp.argmin(jnp.sum((track.sample_xy - point[:2]) ** 2, axis=1))


def _step_from_sample(track: "Track", point, k):
    """:func:`_newton_step` from the coarse sample ``k``, with the sample's stored
    position and tangent (the centreline's rule from a sample is zero at it)."""
    s = track.sample_s[k]
    return _newton_update(s, point[:2] - track.sample_xy[k], track.sample_tangent[k],
                          curvature(track, s))


def _as_point(point) -> Float[Array, "3"]:
    p = jnp.asarray(point, dtype=jnp.float64)
    if p.shape != (3,):
        raise ValueError(f"point must have shape (3,) (global X, Y, Z in m), got {p.shape}")
    return p


def project(
    track: "Track",
    point: Float[ArrayLike, "3"],
    s_guess: Float[ArrayLike, ""] | None = None,
    iterations: int = 2,
) -> Float[Array, ""]:
    """Arc length [m] of the track cross-section whose normal plane contains ``point``.

    **Arguments:**
        track: the track.
        point: global position ``(X, Y, Z)`` [m], within a few metres of the centreline.
        s_guess: initial arc length [m]; default the nearest coarse centreline sample.
        iterations: Newton steps before the final differentiable step (static).

    **Returns:** scalar ``s`` [m] with ``(point - centreline(s)) . t(s) = 0``.
    Differentiable in ``point`` and the track parameters (implicit derivative).
    """
    return project_onto_centreline(track, point, s_guess, iterations)[0]


def project_onto_centreline(track: "Track", point, s_guess=None, iterations: int = 2):
    """:func:`project` with the centreline there: ``(s [m], centreline point (3,) [m],
    (cos h, sin h))`` at ``s``, from the last Newton step's evaluation of the centreline
    (:func:`_last_step`: within rounding of :func:`centreline_and_frame` at ``s``, one
    evaluation fewer)."""
    p = _as_point(point)
    track_ng, p_ng = jax.lax.stop_gradient((track, p))
    if s_guess is None:
        k = _nearest_sample(track_ng, p_ng)
        if iterations > 0:  # the first step from the sample's own data
            s0, iterations = _step_from_sample(track_ng, p_ng, k), iterations - 1
        else:
            s0 = track_ng.sample_s[k]
    else:
        s0 = jnp.asarray(s_guess, dtype=jnp.float64)
        if s0.ndim != 0:
            raise ValueError(f"s_guess must be a scalar arc length, got shape {s0.shape}")
    s = jax.lax.fori_loop(
        0, iterations, lambda _, s: _newton_step(track_ng, p_ng, s), jax.lax.stop_gradient(s0)
    )
    return _last_step(track, p, jax.lax.stop_gradient(s))


def to_track_coordinates(
    track: "Track", point: Float[ArrayLike, "3"], s_guess: Float[ArrayLike, ""] | None = None
) -> tuple[Float[Array, ""], Float[Array, ""], Float[Array, ""]]:
    """Track coordinates ``(s, lateral, vertical)`` [m] of a global ``point`` [m].

    ``s`` from :func:`project`; ``lateral`` along the canted ``n`` (positive left) and
    ``vertical`` along the canted ``b`` (positive up) of the track frame at ``s``.
    """
    p = _as_point(point)
    s, centre, tangent = project_onto_centreline(track, p, s_guess)
    frame = frame_from_cos_sin(tangent, _cant_cos_sin(track, s))
    d = p - centre
    return s, d @ frame[:, 1], d @ frame[:, 2]


def from_track_coordinates(
    track: "Track",
    s: Float[ArrayLike, ""],
    lateral: Float[ArrayLike, ""],
    vertical: Float[ArrayLike, ""],
) -> Float[Array, "3"]:
    """Global point [m] at track coordinates: ``centreline(s) + lateral n + vertical b``
    (canted frame at ``s``; ``lateral`` [m] positive left, ``vertical`` [m] up)."""
    centre, frame = centreline_and_frame(track, s)
    return (
        centre
        + jnp.asarray(lateral, dtype=jnp.float64) * frame[:, 1]
        + jnp.asarray(vertical, dtype=jnp.float64) * frame[:, 2]
    )
