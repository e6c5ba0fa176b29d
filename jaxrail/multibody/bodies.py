"""Rigid bodies in Cartesian coordinates with Euler parameters (Nikravesh, ch. 6, 11).

Coordinates: body i has q_i = (r_i, p_i) (7,), r_i [m] the global position of its centre
of mass and p_i its Euler parameters (scalar first, see `quaternion`). The system
vector is q = (q_0, ..., q_{n-1}) (7 n,). Velocities are the time derivatives
qdot = (rdot_i, pdot_i), **not** angular velocities; `velocities_from_twists` builds them.

With omega' = 2 G pdot the kinetic energy of body i is

    T_i = 1/2 m rdot^T rdot + 2 pdot^T G^T J' G pdot,

so its mass matrix is diag(m I3, 4 G^T J' G) and Lagrange's equations give the
quadratic velocity vector h_p = 8 Gdot^T J' Gdot p (Gdot = G(pdot)) on the
right-hand side: M qddot + Phi_q^T lambda = g + h. The 4 x 4 block is singular along
p; the normalisation constraint p^T p = 1 (in `joints`) removes that direction.
"""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from . import quaternion as qt


@dataclasses.dataclass(frozen=True)
class RigidBody:
    """Build-time description of one rigid body (turned into arrays by build_system).

    Arguments:
        name: unique name, used to refer to the body in joints and force elements.
        mass: m [kg] > 0.
        inertia: about the centre of mass in the body frame [kg m^2]: principal moments
            (Ixx, Iyy, Izz) (3,) or a symmetric positive definite tensor (3, 3).
    """

    name: str
    mass: float
    inertia: object

    def inertia_tensor(self) -> np.ndarray:
        """The (3, 3) inertia tensor [kg m^2]; ValueError if it is not valid."""
        j = np.asarray(self.inertia, dtype=np.float64)
        if j.shape == (3,):
            j = np.diag(j)
        if j.shape != (3, 3):
            raise ValueError(
                f"inertia of body {self.name!r} must have shape (3,) or (3, 3), "
                f"got {j.shape}"
            )
        if not np.allclose(j, j.T, rtol=1e-12, atol=1e-12 * np.abs(j).max()):
            raise ValueError(f"inertia of body {self.name!r} must be symmetric")
        if not np.all(np.linalg.eigvalsh(j) > 0.0):
            raise ValueError(f"inertia of body {self.name!r} must be positive definite")
        if not (np.isfinite(self.mass) and self.mass > 0.0):
            raise ValueError(f"mass of body {self.name!r} must be > 0, got {self.mass}")
        return j


class BodyParams(eqx.Module):
    """Traced inertial parameters of all n bodies.

    Fields:
        mass: (n,) [kg].
        inertia: (n, 3, 3) [kg m^2], about each centre of mass, body frame.
    """

    mass: Float[Array, " n"]
    inertia: Float[Array, "n 3 3"]


def split_coordinates(q: Float[ArrayLike, " 7n"]) -> tuple[Array, Array]:
    """(r (n, 3) [m], p (n, 4)) from the system vector q (7 n,); also for qdot."""
    qq = jnp.reshape(jnp.asarray(q, dtype=jnp.float64), (-1, 7))
    return qq[:, :3], qq[:, 3:]


def join_coordinates(r: Float[ArrayLike, "n 3"], p: Float[ArrayLike, "n 4"]) -> Array:
    """The system vector (7 n,) from positions r (n, 3) and Euler parameters p (n, 4)."""
    r = jnp.asarray(r, dtype=jnp.float64)
    p = jnp.asarray(p, dtype=jnp.float64)
    return jnp.concatenate([r, p], axis=1).reshape(-1)


def velocities_from_twists(
    q: Float[ArrayLike, " 7n"], v: Float[ArrayLike, "n 3"], omega: Float[ArrayLike, "n 3"]
) -> Array:
    """qdot (7 n,) from centre velocities v [m/s] and angular velocities omega [rad/s],
    both (n, 3) in the global frame."""
    _, p = split_coordinates(q)
    pdot = jax.vmap(qt.pdot_from_omega_global)(p, jnp.asarray(omega, dtype=jnp.float64))
    return join_coordinates(v, pdot)


def body_mass_matrix(mass, inertia, p) -> Float[Array, "7 7"]:
    """diag(m I3, 4 G^T J' G) (7, 7) of one body; mass [kg], inertia (3, 3), p (4,)."""
    g = qt.g_matrix(p)
    m_rot = 4.0 * g.T @ inertia @ g
    top = jnp.concatenate([mass * jnp.eye(3), jnp.zeros((3, 4))], axis=1)
    bottom = jnp.concatenate([jnp.zeros((4, 3)), m_rot], axis=1)
    return jnp.concatenate([top, bottom], axis=0)


def body_quadratic_velocity(inertia, p, pdot) -> Float[Array, " 7"]:
    """Quadratic velocity vector h (7,) = (0, 8 Gdot^T J' Gdot p) of one body [N, N m].

    Gdot = G(pdot) (G is linear in p). h enters the right-hand side: M qddot = g + h.
    Equivalent, up to a multiple of p, to -2 G^T (omega' x J' omega').
    """
    gdot = qt.g_matrix(pdot)
    h_p = 8.0 * gdot.T @ (inertia @ (gdot @ p))
    return jnp.concatenate([jnp.zeros(3), h_p])


def body_kinetic_energy(mass, inertia, p, rdot, pdot) -> Float[Array, ""]:
    """T [J] of one body: 1/2 m v^2 + 1/2 omega'^T J' omega', omega' = 2 G pdot."""
    w = 2.0 * qt.g_matrix(p) @ pdot
    return 0.5 * mass * rdot @ rdot + 0.5 * w @ (inertia @ w)


def body_angular_momentum(mass, inertia, r, p, rdot, pdot) -> Float[Array, " 3"]:
    """Angular momentum [kg m^2/s] (3,) of one body about the global origin, global.

    m r x rdot + A J' omega'.
    """
    w = 2.0 * qt.g_matrix(p) @ pdot
    return mass * jnp.cross(r, rdot) + qt.rotation_matrix(p) @ (inertia @ w)


def body_pose(q: Float[ArrayLike, " 7n"], i: int) -> tuple[Array, Array]:
    """(r_i (3,) [m], A_i (3, 3)) of body i: centre position and body-to-global matrix."""
    r, p = split_coordinates(q)
    return r[i], qt.rotation_matrix(p[i])


def angular_velocity(
    q: Float[ArrayLike, " 7n"], qdot: Float[ArrayLike, " 7n"], i: int
) -> tuple[Array, Array]:
    """(omega (3,) global, omega' (3,) body frame) [rad/s] of body i."""
    _, p = split_coordinates(q)
    _, pdot = split_coordinates(qdot)
    return 2.0 * qt.e_matrix(p[i]) @ pdot[i], 2.0 * qt.g_matrix(p[i]) @ pdot[i]


def point_position(r, p, point) -> Float[Array, " 3"]:
    """Global position [m] (3,) of the body point with body-frame coordinates `point`."""
    return r + qt.rotation_matrix(p) @ point


def point_velocity(p, rdot, pdot, point) -> Float[Array, " 3"]:
    """Global velocity [m/s] (3,) of a body point: rdot + d/dt(A) point.

    d/dt A is the exact derivative of the quadratic A(p) along pdot, so that velocities
    are consistent with `point_position` even when |p| is not exactly 1.
    """
    return rdot + _rotation_rate(p, pdot) @ point


def _rotation_rate(p, pdot):
    """dA/dt (3, 3) along pdot: A is quadratic in p, so its derivative is bilinear."""
    e0, e = p[0], p[1:]
    d0, d = pdot[0], pdot[1:]
    return 2.0 * (
        2.0 * e0 * d0 * jnp.eye(3)
        + jnp.outer(d, e)
        + jnp.outer(e, d)
        + d0 * qt.skew(e)
        + e0 * qt.skew(d)
    )
