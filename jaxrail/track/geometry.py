"""Track geometry at arc length ``s``: centreline, heading, curvature, cant, frames, rails.

Conventions (docs/design.md §3):

- Global frame ``X, Y`` horizontal, ``Z`` up. The track is **planar**: no vertical
  gradient; the centreline lies in ``Z = 0``.
- Track frame at arc length ``s`` [m]: ``t`` along the track (direction of travel),
  ``n`` lateral to the **left**, ``b`` up; columns of the ``(3, 3)`` matrix
  ``[t n b]``, orthonormal and right-handed (``t x n = b``).
- Curvature ``kappa`` [1/m] is positive for a **left** curve (the track turns toward
  ``+n``), negative for a right curve.
- Cant: superelevation ``e`` [m] of one rail over the other, across the rail-centre
  distance ``track.rail_centre_distance`` (default 1.5 m); cant angle
  ``phi = arcsin(e / rail_centre_distance)`` [rad]. Both are **signed**: positive
  banks the track toward the left (right rail raised, the normal cant of a left curve),
  negative toward the right (left rail raised, the normal cant of a right curve). The
  track frame is rolled about ``t`` through the centreline by ``-phi``, so that ``b``
  leans toward the inside of the curve and the centreline stays at ``Z = 0``:
  ``t = (cos h, sin h, 0)``, ``n = (-sin h cos phi, cos h cos phi, -sin phi)``,
  ``b = (-sin h sin phi, cos h sin phi, cos phi)`` with ``h`` the heading.

Within a segment of local distance ``sigma = s - s_start`` the heading is quadratic,
``h = h0 + kappa0 sigma + rate sigma^2 / 2``; ``X, Y`` are the integrals of ``cos h``
and ``sin h``, evaluated for every segment kind (straight, arc, clothoid) by
fixed-node Gauss-Legendre rules: from the segment's start with 24 nodes where the
layout is built (the segment starts and the track's coarse samples, for heading
changes per segment up to about 2 pi), and at a point ``s`` from the nearest coarse
sample of its segment with 8 (:func:`centreline_position`: at most half a sample
spacing, over which the heading turns by at most 2 pi / (2 x 8) with the least
samples a layout takes). Both are within 1e-12 m of the exact integral.

Beyond the ends (``s < 0`` or ``s > total length``) the first and last segments are
**extended by their own law**: a straight end (the usual case) continues as a
straight line, an arc end as the same circle. Curvature and cant stay at their end
values (a layout never ends with a transition).

Every function takes a scalar ``s``; use ``jax.vmap`` for arrays. All are pure JAX
and jit/vmap/grad-able in ``s`` and in the track's parameters.
"""

from typing import TYPE_CHECKING

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float


if TYPE_CHECKING:
    from .layout import Track

# Gauss-Legendre nodes and weights on [-1, 1]; numpy constants, cast at use so that
# importing this module does not depend on JAX's float64 switch.
GAUSS_LEGENDRE_NODES = 24
# from the nearest coarse sample (module docstring); the layout takes at least
# MIN_SAMPLES_PER_SEGMENT samples per segment for it
FROM_SAMPLE_NODES = 8
MIN_SAMPLES_PER_SEGMENT = 8


def local_heading(heading0, curvature0, curvature_rate, sigma):
    """Heading [rad] at local distance ``sigma`` [m] of a segment (quadratic law)."""
    return heading0 + sigma * (curvature0 + 0.5 * curvature_rate * sigma)


def local_offset(heading0, curvature0, curvature_rate, sigma, nodes=GAUSS_LEGENDRE_NODES):
    """Plane offset ``(dX, dY)`` [m] from a segment's start to local distance ``sigma``.

    Gauss-Legendre quadrature of ``(cos h, sin h)`` over ``[0, sigma]`` with ``nodes``
    nodes (static); valid for negative ``sigma`` too (extension before the start). The
    layout builder places the segment starts and coarse samples with it, and
    :func:`centreline_position` integrates from the nearest sample.
    """
    nodes_x, weights = np.polynomial.legendre.leggauss(nodes)
    x = jnp.asarray(nodes_x, dtype=jnp.float64)
    w = jnp.asarray(weights, dtype=jnp.float64)
    tau = 0.5 * sigma * (1.0 + x)
    h = local_heading(heading0, curvature0, curvature_rate, tau)
    half = 0.5 * sigma
    return half * jnp.sum(w * jnp.cos(h)), half * jnp.sum(w * jnp.sin(h))


def _locate(track: "Track", s):
    """Segment index and local distance [m] for scalar arc length ``s`` [m]."""
    s = jnp.asarray(s, dtype=jnp.float64)
    if s.ndim != 0:
        raise ValueError(f"s must be a scalar arc length, got shape {s.shape}; use jax.vmap")
    # compare_all: no loop (cheap to compile and vmap) for the few tens of segments.
    i = jnp.searchsorted(track.segment_start, s, side="right", method="compare_all") - 1
    i = jnp.clip(i, 0, track.n_segments - 1)
    return i, s - track.segment_start[i]


def _heading_and_curvature(track: "Track", s):
    i, sigma = _locate(track, s)
    h = local_heading(
        track.heading_start[i], track.curvature_start[i], track.curvature_rate[i], sigma
    )
    kappa = track.curvature_start[i] + track.curvature_rate[i] * sigma
    return h, kappa


def centreline_position(track: "Track", s: Float[ArrayLike, ""]) -> Float[Array, "3"]:
    """Centreline point ``(X, Y, 0)`` [m], global frame, at arc length ``s`` [m]:
    integrated from the nearest coarse sample of its segment (``track.sample_s``,
    ``sample_xy``: ``k + 1`` per segment, ends included, evenly spaced), so that a
    short rule suffices (module docstring)."""
    i, sigma = _locate(track, s)
    per_segment = track.sample_s.shape[0] // track.n_segments  # k + 1 (static)
    spacing = track.segment_length[i] / (per_segment - 1)
    j = jnp.clip(jnp.round(sigma / spacing), 0, per_segment - 1)
    at = j * spacing  # the sample's local distance [m]
    curvature0, rate = track.curvature_start[i], track.curvature_rate[i]
    dx, dy = local_offset(local_heading(track.heading_start[i], curvature0, rate, at),
                          curvature0 + rate * at, rate, sigma - at, nodes=FROM_SAMPLE_NODES)
    sample = track.sample_xy[i * per_segment + j.astype(jnp.int32)]
    return jnp.stack([sample[0] + dx, sample[1] + dy, jnp.zeros_like(dx)])


def heading(track: "Track", s: Float[ArrayLike, ""]) -> Float[Array, ""]:
    """Heading [rad] of the tangent ``t``, counter-clockwise from global ``+X``."""
    return _heading_and_curvature(track, s)[0]


def curvature(track: "Track", s: Float[ArrayLike, ""]) -> Float[Array, ""]:
    """Signed horizontal curvature [1/m] at ``s`` [m]; > 0 left curve, < 0 right."""
    return _heading_and_curvature(track, s)[1]


def superelevation(track: "Track", s: Float[ArrayLike, ""]) -> Float[Array, ""]:
    """Signed cant [m] at ``s`` [m]: > 0 right rail raised (banked left), < 0 left raised.

    Linear in ``s`` along a transition, constant on straights (zero) and arcs."""
    i, sigma = _locate(track, s)
    return track.superelevation_start[i] + track.superelevation_rate[i] * sigma


def cant_angle(track: "Track", s: Float[ArrayLike, ""]) -> Float[Array, ""]:
    """Signed cant angle [rad] ``arcsin(superelevation / rail_centre_distance)``."""
    return jnp.arcsin(superelevation(track, s) / track.rail_centre_distance)


def frame_from_angles(heading_angle, cant) -> Float[Array, "3 3"]:
    """``[t n b]`` (columns) for a heading [rad] and a signed cant angle [rad]."""
    ch, sh = jnp.cos(heading_angle), jnp.sin(heading_angle)
    cp, sp = jnp.cos(cant), jnp.sin(cant)
    zero = jnp.zeros_like(ch)
    t = jnp.stack([ch, sh, zero])
    n = jnp.stack([-sh * cp, ch * cp, -sp])
    b = jnp.stack([-sh * sp, ch * sp, cp])
    return jnp.stack([t, n, b], axis=1)


def track_frame(track: "Track", s: Float[ArrayLike, ""]) -> Float[Array, "3 3"]:
    """Track frame at ``s`` [m]: ``(3, 3)`` matrix, columns ``[t, n, b]`` in global axes.

    ``t`` horizontal along the track, ``n`` to the left and ``b`` up, both rolled about
    ``t`` by the cant (``b`` leans toward the inside of the curve)."""
    return frame_from_angles(heading(track, s), cant_angle(track, s))


def _side_sign(side) -> Float[Array, ""]:
    """+1.0 for the left rail, -1.0 for the right; accepts 'left'/'right' or +-1."""
    if isinstance(side, str):
        if side == "left":
            return jnp.asarray(1.0, dtype=jnp.float64)
        if side == "right":
            return jnp.asarray(-1.0, dtype=jnp.float64)
        raise ValueError(f"side must be 'left', 'right', +1 or -1, got {side!r}")
    if isinstance(side, (int, float, np.integer, np.floating)) and side not in (1, -1):
        raise ValueError(f"side must be 'left', 'right', +1 or -1, got {side!r}")
    return jnp.asarray(side, dtype=jnp.float64)
