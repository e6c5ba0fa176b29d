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
samples a layout takes). Both are within 1e-12 m of the exact integral. At ``s`` the
rule rotates by the sample's tangent (``track.sample_tangent``: its ``cos`` and ``sin``
taken where the layout is built) and the nodes' small turns from it by their series
(:func:`small_angle_cos_sin`): XLA:CPU runs ``jnp.cos`` and ``jnp.sin`` as a scalar
library call per element (about 10 ns each), the series in vector multiplications.

Beyond the ends (``s < 0`` or ``s > total length``) the first and last segments are
**extended by their own law**: a straight end (the usual case) continues as a
straight line, an arc end as the same circle. Curvature and cant stay at their end
values (a layout never ends with a transition).

Every function takes a scalar ``s``; use ``jax.vmap`` for arrays. All are pure JAX
and jit/vmap/grad-able in ``s`` and in the track's parameters.
"""

import math
from typing import TYPE_CHECKING

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..compilation.fusion import computed_once


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


# Taylor coefficients of cos and sin in x^2 (cos: (-1)^k / (2k)!, sin: (-1)^k / (2k+1)!),
# highest first for Horner's rule; 9 terms each: truncation under 3e-18 for |x| <= 0.8
_COS_SERIES = tuple((-1.0) ** k / math.factorial(2 * k) for k in range(8, -1, -1))
_SIN_SERIES = tuple((-1.0) ** k / math.factorial(2 * k + 1) for k in range(8, -1, -1))


def small_angle_cos_sin(angle):
    """``(cos angle, sin angle)`` by their Taylor series, for ``|angle| <= 0.8`` rad
    (within an ulp there; the centreline's turn from its nearest sample, at most a
    sixteenth of a segment's turn, stays below it for segments turning under two
    revolutions). Plain multiplications, which XLA vectorises; ``jnp.cos`` and
    ``jnp.sin`` are a scalar library call per element on XLA:CPU."""
    x2 = angle * angle
    cos, sin = _COS_SERIES[0], _SIN_SERIES[0]
    for c, s in zip(_COS_SERIES[1:], _SIN_SERIES[1:]):
        cos, sin = cos * x2 + c, sin * x2 + s
    return cos, angle * sin


def _rotated(cos_sin, vector):
    """``vector`` (x, y) turned counter-clockwise by the angle of ``cos_sin``."""
    (c, s), (x, y) = cos_sin, vector
    return c * x - s * y, s * x + c * y


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


def _from_sample(track: "Track", s):
    """The centreline at ``s`` [m] from the nearest coarse sample of its segment
    (``track.sample_s``, ``sample_xy``, ``sample_tangent``: ``k + 1`` per segment, ends
    included, evenly spaced): ``(position (3,), (cos h, sin h))``, ``h`` the heading at
    ``s``. The offset from the sample is a short Gauss-Legendre rule (module docstring)
    of the sample's tangent turned by the heading's change from it."""
    i, sigma = _locate(track, s)
    per_segment = track.sample_s.shape[0] // track.n_segments  # k + 1 (static)
    spacing = track.segment_length[i] / (per_segment - 1)
    j = jnp.clip(jnp.round(sigma / spacing), 0, per_segment - 1)
    at = j * spacing  # the sample's local distance [m]
    curvature0, rate = track.curvature_start[i], track.curvature_rate[i]
    k = i * per_segment + j.astype(jnp.int32)
    tangent = track.sample_tangent[k, 0], track.sample_tangent[k, 1]
    sample_curvature = curvature0 + rate * at
    u = sigma - at
    nodes_x, weights = np.polynomial.legendre.leggauss(FROM_SAMPLE_NODES)
    tau = 0.5 * u * (1.0 + jnp.asarray(nodes_x, dtype=jnp.float64))
    turn_cos, turn_sin = small_angle_cos_sin(local_heading(0.0, sample_curvature, rate, tau))
    w = 0.5 * u * jnp.asarray(weights, dtype=jnp.float64)
    dx, dy = _rotated(tangent, (jnp.sum(w * turn_cos), jnp.sum(w * turn_sin)))
    sample = track.sample_xy[k]
    position = jnp.stack([sample[0] + dx, sample[1] + dy, jnp.zeros_like(dx)])
    cos, sin = _rotated(tangent, small_angle_cos_sin(local_heading(0.0, sample_curvature,
                                                                    rate, u)))
    # (cos h, sin h): read by each of the frame's entries
    return position, computed_once(cos, sin)


def centreline_position(track: "Track", s: Float[ArrayLike, ""]) -> Float[Array, "3"]:
    """Centreline point ``(X, Y, 0)`` [m], global frame, at arc length ``s`` [m]:
    integrated from the nearest coarse sample of its segment, so that a short rule
    suffices (module docstring)."""
    return _from_sample(track, s)[0]


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


def _cant_cos_sin(track: "Track", s):
    """``(cos phi, sin phi)`` of the cant angle at ``s`` [m], without the angle: ``sin
    phi = e / rail_centre_distance`` (|e| below it, checked by the layout)."""
    sin = superelevation(track, s) / track.rail_centre_distance
    return jnp.sqrt(1.0 - sin * sin), sin


def frame_from_cos_sin(heading_cos_sin, cant_cos_sin) -> Float[Array, "3 3"]:
    """``[t n b]`` (columns) from ``(cos, sin)`` of the heading and of the signed cant
    angle."""
    (ch, sh), (cp, sp) = heading_cos_sin, cant_cos_sin
    zero = jnp.zeros_like(ch)
    t = jnp.stack([ch, sh, zero])
    n = jnp.stack([-sh * cp, ch * cp, -sp])
    b = jnp.stack([-sh * sp, ch * sp, cp])
    return jnp.stack([t, n, b], axis=1)


def centreline_and_frame(track: "Track", s: Float[ArrayLike, ""]):
    """``(centreline point (3,) [m], track frame (3, 3))`` at ``s`` [m]: both of
    :func:`centreline_position` and :func:`track_frame` from one evaluation."""
    position, tangent = _from_sample(track, s)
    return position, frame_from_cos_sin(tangent, _cant_cos_sin(track, s))


def track_frame(track: "Track", s: Float[ArrayLike, ""]) -> Float[Array, "3 3"]:
    """Track frame at ``s`` [m]: ``(3, 3)`` matrix, columns ``[t, n, b]`` in global axes.

    ``t`` horizontal along the track, ``n`` to the left and ``b`` up, both rolled about
    ``t`` by the cant (``b`` leans toward the inside of the curve)."""
    return centreline_and_frame(track, s)[1]


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
