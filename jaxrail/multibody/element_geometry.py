"""Where a force element's two points are: the geometry its deformation coordinates
are made from (points in the frames of their bodies, results global)."""

import jax.numpy as jnp

from . import quaternion as qt


def separation(qi, qj, e):
    """(A_i, A_j, d = r_Pj - r_Pi (3,) [m], global) of one element's two points
    ``e.point_i``, ``e.point_j`` on the bodies with coordinates qi, qj (7,)."""
    a_i, a_j = qt.rotation_matrix(qi[3:]), qt.rotation_matrix(qj[3:])
    d = qj[:3] + qt.matvec(a_j, e.point_j) - qi[:3] - qt.matvec(a_i, e.point_i)
    return a_i, a_j, d


def line_length(qi, qj, e):
    """(1,) the distance [m] between the element's two points; at zero length, where
    the direction is undefined, 0 with a zero derivative (no force)."""
    _, _, d = separation(qi, qj, e)
    d2 = qt.dot(d, d)[None]
    pos = d2 > 0.0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, d2, 1.0)), 0.0)
