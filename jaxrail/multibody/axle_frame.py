"""The non-spinning frame of an axle: where a wheelset carries its axleboxes.

A wheelset spins about its own y axis (the axle). Its axleboxes do not: they follow
the axle's yaw and roll and keep their x axis level. Instead of an axlebox body on a
revolute joint (five constraint rows per axle in eq. 19), the force elements of an
*axle body* (``System.axle_bodies``) attach to that frame of the wheelset itself:

    a = A(p) e_y                        the axle's direction (global)
    psi = atan2(-a_x, a_y)              its yaw about the global z
    phi = atan2(a_z, |(a_x, a_y)|)      its roll (the tilt of the axle)
    p_axle = q_z(psi) * q_x(phi)        Euler parameters of the axle frame

The frame's y axis is the axle, its x axis is level and square to it, whatever the
wheelset's spin; p_axle depends on the direction of p only (unit p_axle for any |p|).
An element then sees the body at ``(r, p_axle)`` with the rates ``(rdot, J pdot)``,
J = d p_axle / d p, and its generalized force g' on those coordinates acts on the
wheelset as ``J^T g'`` (virtual work), which is tangent to p because J p = 0.

The axlebox body's own pitch about the axle, which only a soft spring held, is
dropped: nothing else restrains it, so that spring carries no moment at rest and the
frame needs no pitch of its own (:mod:`jaxrail.vehicles.axleboxes`). The frame's
pitch is then tied to its yaw and roll (its x axis stays level), so a moment about the
axle that an element puts on the frame (a deflected bushing's d x F) turns the wheelset
about the frame's z axis by tan(roll) times that moment, where an axlebox body would
pitch freely instead: on a 0.07 rad cant, with millimetre deflections under tens of
kN, a few N m.
"""

import jax
import jax.numpy as jnp
import numpy as np

from . import quaternion as qt


def axle_direction(p):
    """The unit axle direction (3,) (the body's y axis, global) of Euler parameters p
    (4,), of any norm."""
    return qt.rotation_matrix(qt.normalize(p))[:, 1]


def axle_rotation(p):
    """Euler parameters (4,) of the axle frame (module docstring) of a body with Euler
    parameters p (4,): its y axis along the body's, its x axis level."""
    a = axle_direction(p)
    half_yaw = 0.5 * jnp.arctan2(-a[0], a[1])
    half_roll = 0.5 * jnp.arctan2(a[2], jnp.sqrt(a[0] ** 2 + a[1] ** 2))
    cy, sy = jnp.cos(half_yaw), jnp.sin(half_yaw)
    cr, sr = jnp.cos(half_roll), jnp.sin(half_roll)
    return jnp.stack([cy * cr, cy * sr, sy * sr, sy * cr])


class ElementView:
    """The coordinates and rates the force elements see, and the map of their
    generalized forces back onto the bodies' own.

    ``q``, ``qdot`` (7 n,): the bodies' as given, with each axle body's Euler
    parameters and their rates replaced by its axle frame's; ``pull(g)``: the
    generalized forces (7 n,) on those coordinates as forces on the bodies'.
    """

    def __init__(self, axle_bodies, q, qdot=None):
        self.bodies = np.asarray(axle_bodies, dtype=int)
        if self.bodies.size == 0:
            self.q, self.qdot, self._jacobian = q, qdot, None
            return
        n = q.shape[0] // 7
        body = q.reshape(n, 7)
        p = body[self.bodies, 3:]
        self._jacobian = jax.vmap(jax.jacfwd(axle_rotation))(p)  # (k, 4, 4)
        self.q = body.at[self.bodies, 3:].set(jax.vmap(axle_rotation)(p)).reshape(-1)
        if qdot is None:
            self.qdot = None
        else:
            rate = qdot.reshape(n, 7)
            turned = qt.matvec(self._jacobian, rate[self.bodies, 3:])
            self.qdot = rate.at[self.bodies, 3:].set(turned).reshape(-1)

    def pull(self, g):
        """J^T g on the axle bodies' Euler parameters; g (7 n,) unchanged elsewhere."""
        if self._jacobian is None:
            return g
        body = g.reshape(-1, 7)
        back = jnp.einsum("kij,ki->kj", self._jacobian, body[self.bodies, 3:])
        return body.at[self.bodies, 3:].set(back).reshape(-1)
