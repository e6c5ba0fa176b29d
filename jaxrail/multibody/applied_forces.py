"""Generalized forces of forces and torques applied to a body, in the Euler-parameter
(pdot) convention.

A force f (global, [N]) at the body point s' [m] (body frame) and a torque n (global,
[N m]) on body i do the virtual work f . delta r_P + n . delta pi, which in the
coordinates q_i = (r, p) is the generalized force

    g_r = f,     g_p = 2 G^T n',     n' = s' x (A^T f) + A^T n   (body frame).

The component of g_p along p does no work on the unit sphere (it only changes the
normalisation multiplier); :func:`tangent` removes it.
"""

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from . import quaternion as qt


def tangent(p, g_p):
    """Remove the component of g_p along p (it does no work while |p| = 1)."""
    return g_p - p * qt.dot(p, g_p) / qt.dot(p, p)


def point_force(p, point, force) -> Float[Array, " 7"]:
    """Generalized force (7,) of a global force [N] at body point `point` [m] (body
    frame) of a body with Euler parameters p: (f, 2 G^T (s' x A^T f))."""
    a = qt.rotation_matrix(p)
    n_body = jnp.cross(point, qt.matvec(a.T, force))
    return jnp.concatenate([force, 2.0 * qt.matvec(qt.g_matrix(p).T, n_body)])


def body_torque(p, torque) -> Float[Array, " 7"]:
    """Generalized force (7,) of a global torque [N m] on a body: (0, 2 G^T A^T n)."""
    n_body = qt.matvec(qt.rotation_matrix(p).T, torque)
    g_p = 2.0 * qt.matvec(qt.g_matrix(p).T, n_body)
    return jnp.concatenate([jnp.zeros(3), g_p])


def centre_loads(q, forces, torques) -> Float[Array, " 7n"]:
    """Generalized forces (7 n,) of global forces (n, 3) [N] at the centres of mass and
    global torques (n, 3) [N m]; the form of the `external` hook."""
    n = q.shape[0] // 7
    p = q.reshape(n, 7)[:, 3:]
    g_p = jax.vmap(lambda pi, ni: body_torque(pi, ni)[3:])(p, torques)
    return jnp.concatenate([forces, g_p], axis=1).reshape(-1)


def gravity_forces(mass, gravity, n) -> Float[Array, " 7n"]:
    """Generalized gravity forces (7 n,): m_i g at each centre; gravity (3,) [m/s^2]."""
    f = mass[:, None] * gravity[None, :]
    return jnp.concatenate([f, jnp.zeros((n, 4))], axis=1).reshape(-1)
