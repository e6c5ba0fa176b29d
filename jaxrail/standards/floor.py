"""What an accelerometer fixed to a body reads: the specific force at a body point
(its acceleration less gravity) in the body's own axes, from the states and
accelerations of a run (``bodies/q``, ``bodies/qdot``, ``bodies/qddot`` of a results
file, or a :class:`jaxrail.simulation.SimulationResult`). The carbody floor points of
EN 12299 are such points; on a level carbody at rest the vertical reading is +g."""

import jax
import numpy as np

from ..multibody import quaternion as qt

from .._constants import GRAVITY as _G

GRAVITY = np.array([0.0, 0.0, -_G])  # [m/s^2] global, the vehicles' gravity


def floor_accelerations(q, qdot, qddot, body: int, point, gravity=GRAVITY) -> np.ndarray:
    """Specific force (T, 3) [m/s^2] at ``point`` (3,) [m, body frame] of ``body`` in
    that body's axes (x forward, y left, z up for a carbody), from ``q``, ``qdot``,
    ``qddot`` (T, 7 n) or (T, n, 7): ``A^T (r'' + alpha x s + omega x (omega x s) - g)``
    with ``s = A point``, ``omega = 2 E pdot`` and ``alpha = 2 E pddot`` (E pdot's own
    rate term, 2 Edot pdot, vanishes)."""
    shape = (len(np.asarray(q)), -1, 7)
    q, qdot, qddot = (np.asarray(x, dtype=np.float64).reshape(shape)[:, body]
                      for x in (q, qdot, qddot))
    rotation = np.asarray(jax.vmap(qt.rotation_matrix)(q[:, 3:]))
    e = np.asarray(jax.vmap(qt.e_matrix)(q[:, 3:]))
    arm = rotation @ np.asarray(point, dtype=np.float64)
    omega = 2.0 * np.einsum("tij,tj->ti", e, qdot[:, 3:])
    alpha = 2.0 * np.einsum("tij,tj->ti", e, qddot[:, 3:])
    acceleration = (qddot[:, :3] + np.cross(alpha, arm)
                    + np.cross(omega, np.cross(omega, arm)) - np.asarray(gravity))
    return np.einsum("tji,tj->ti", rotation, acceleration)
