"""Rigid bodies in Cartesian coordinates with Euler parameters (Nikravesh, ch. 6, 11).

Coordinates: body i has q_i = (r_i, p_i) (7,), r_i [m] the global position of its centre
of mass and p_i its Euler parameters (scalar first, see `quaternion`). The system
vector is q = (q_0, ..., q_{n-1}) (7 n,). Velocities are the time derivatives
qdot = (rdot_i, pdot_i), **not** angular velocities (`velocities_from_twists` builds
them from angular velocities).

With omega' = 2 G pdot the kinetic energy of body i is

    T_i = 1/2 m rdot^T rdot + 2 pdot^T G^T J' G pdot,

so its mass matrix is diag(m I3, 4 G^T J' G) and Lagrange's equations give the
quadratic velocity vector h_p = 8 Gdot^T J' Gdot p (Gdot = G(pdot)) on the
right-hand side: M qddot + Phi_q^T lambda = g + h. The 4 x 4 block is singular along
p; the normalisation constraint p^T p = 1 (in `joints`) removes that direction.
"""

import dataclasses
from typing import NamedTuple

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
    """System vector (7 n,) from positions r (n, 3) and Euler parameters p (n, 4)."""
    r = jnp.asarray(r, dtype=jnp.float64)
    p = jnp.asarray(p, dtype=jnp.float64)
    return jnp.concatenate([r, p], axis=1).reshape(-1)


def velocities_from_twists(
    q: Float[ArrayLike, " 7n"],
    v: Float[ArrayLike, "n 3"],
    omega: Float[ArrayLike, "n 3"],
) -> Array:
    """qdot (7 n,) from centre velocities v [m/s] and angular velocities omega [rad/s],
    both (n, 3) in the global frame."""
    _, p = split_coordinates(q)
    pdot = jax.vmap(qt.pdot_from_omega_global)(p, jnp.asarray(omega, dtype=jnp.float64))
    return join_coordinates(v, pdot)


def body_mass_matrix(mass, inertia, p) -> Float[Array, "7 7"]:
    """diag(m I3, 4 G^T J' G) (7, 7) of one body; mass [kg], inertia (3, 3), p (4,)."""
    g = qt.g_matrix(p)
    m_rot = 4.0 * qt.matmul(g.T, qt.matmul(inertia, g))
    top = jnp.concatenate([mass * jnp.eye(3), jnp.zeros((3, 4))], axis=1)
    bottom = jnp.concatenate([jnp.zeros((4, 3)), m_rot], axis=1)
    return jnp.concatenate([top, bottom], axis=0)


def body_quadratic_velocity(inertia, p, pdot) -> Float[Array, " 7"]:
    """Quadratic velocity vector h (7,) = (0, 8 Gdot^T J' Gdot p) of one body [N, N m].

    Gdot = G(pdot) (G is linear in p). h enters the right-hand side: M qddot = g + h.
    Equivalent, up to a multiple of p, to -2 G^T (omega' x J' omega').
    """
    gdot = qt.g_matrix(pdot)
    h_p = 8.0 * qt.matvec(gdot.T, qt.matvec(inertia, qt.matvec(gdot, p)))
    return jnp.concatenate([jnp.zeros(3), h_p])


def body_kinetic_energy(mass, inertia, p, rdot, pdot) -> Float[Array, ""]:
    """T [J] of one body: 1/2 m v^2 + 1/2 omega'^T J' omega', omega' = 2 G pdot."""
    w = 2.0 * qt.matvec(qt.g_matrix(p), pdot)
    return 0.5 * mass * qt.dot(rdot, rdot) + 0.5 * qt.dot(w, qt.matvec(inertia, w))


def body_angular_momentum(mass, inertia, r, p, rdot, pdot) -> Float[Array, " 3"]:
    """Angular momentum [kg m^2/s] (3,) of one body about the global origin, global.

    m r x rdot + A J' omega'.
    """
    w = 2.0 * qt.matvec(qt.g_matrix(p), pdot)
    spin = qt.matvec(qt.rotation_matrix(p), qt.matvec(inertia, w))
    return mass * jnp.cross(r, rdot) + spin


def body_pose(q: Float[ArrayLike, " 7n"], i: int) -> tuple[Array, Array]:
    """(r_i (3,) [m], A_i (3, 3)) of body i: centre position, body-to-global matrix."""
    r, p = split_coordinates(q)
    return r[i], qt.rotation_matrix(p[i])


def angular_velocity(
    q: Float[ArrayLike, " 7n"], qdot: Float[ArrayLike, " 7n"], i: int
) -> tuple[Array, Array]:
    """(omega (3,) global, omega' (3,) body frame) [rad/s] of body i."""
    _, p = split_coordinates(q)
    _, pdot = split_coordinates(qdot)
    return (2.0 * qt.matvec(qt.e_matrix(p[i]), pdot[i]),
            2.0 * qt.matvec(qt.g_matrix(p[i]), pdot[i]))


def point_position(r, p, point) -> Float[Array, " 3"]:
    """Global position [m] (3,) of the body point `point` (body-frame coordinates)."""
    return r + qt.matvec(qt.rotation_matrix(p), point)


def point_velocity(p, rdot, pdot, point) -> Float[Array, " 3"]:
    """Global velocity [m/s] (3,) of a body point: rdot + d/dt(A) point.

    d/dt A is the exact derivative of the quadratic A(p) along pdot, so that velocities
    are consistent with `point_position` even when |p| is not exactly 1.
    """
    return rdot + qt.matvec(qt.rotation_matrix_rate(p, pdot), point)


class Jet(NamedTuple):
    """Quantities x(q_i, q_j) of a pair of bodies with their derivatives along qdot.

    value x (..., d); jac dx/d(q_i, q_j) (..., d, 14); rate xdot = jac qdot (..., d);
    bias = (jac qdot)_q qdot (..., d), the part of xddot without qddot (gamma = -bias).
    All analytic: A(p) is quadratic in p.
    """

    value: Array
    jac: Array
    rate: Array
    bias: Array


# Rows of the pair kinematics: the element's point and axes on body i, on body j, and
# the separation d = r_Pj - r_Pi.
P_I, X_I, Y_I, Z_I, P_J, X_J, Y_J, Z_J, D = range(9)
_ROW_IS_POINT = np.array([1.0, 0.0, 0.0, 0.0])[:, None]  # (4, 1)
_IS_POINT = _ROW_IS_POINT[:, :, None] * np.eye(3)  # (4, 3, 3): d(row)/dr


def _side_kinematics(q, qdot, point, axes):
    """Value (4, 3), d/dq_i (4, 3, 7), rate, bias of (point, axes) of one body."""
    p, pdot = q[3:], qdot[3:]
    m_p = qt.rotation_tensor(p)
    m_pdot = qt.rotation_tensor(pdot)
    a = qt.matvec(m_p, p) - jnp.eye(3)
    f = jnp.concatenate([point[None], axes], axis=0)  # (4, 3) body frame
    origin = jnp.asarray(_ROW_IS_POINT)
    value = qt.matvec(a, f) + origin * q[:3]
    rate = qt.matvec(2.0 * qt.matvec(m_p, pdot), f) + origin * qdot[:3]
    bias = qt.matvec(2.0 * qt.matvec(m_pdot, pdot), f)
    jac_p = 2.0 * jnp.sum(m_p * f[:, None, :, None], axis=2)  # (4, 3, 4)
    jac = jnp.concatenate([jnp.asarray(_IS_POINT), jac_p], axis=2)
    return value, jac, rate, bias


def pair_kinematics(qi, qj, vi, vj, point_i, axes_i, point_j, axes_j) -> Jet:
    """Jets (9, 3) of the rows P_I, X_I, Y_I, Z_I, P_J, X_J, Y_J, Z_J, D (global).

    Arguments:
        qi, qj, vi, vj: (7,) coordinates and velocities of bodies i and j.
        point_i, point_j: (3,) [m] body-frame points; axes_i, axes_j: (3, 3) body-frame
            axis vectors as rows (e.g. frame.T).
    """
    vi_, ji, ri, bi = _side_kinematics(qi, vi, point_i, axes_i)
    vj_, jj, rj, bj = _side_kinematics(qj, vj, point_j, axes_j)
    zeros = jnp.zeros_like(ji)
    jac = jnp.concatenate(
        [jnp.concatenate([ji, zeros], axis=2), jnp.concatenate([zeros, jj], axis=2)],
        axis=0,
    )
    value = jnp.concatenate([vi_, vj_], axis=0)
    rate = jnp.concatenate([ri, rj], axis=0)
    bias = jnp.concatenate([bi, bj], axis=0)

    def with_d(x):
        return jnp.concatenate([x, (x[P_J] - x[P_I])[None]], axis=0)

    return Jet(with_d(value), with_d(jac), with_d(rate), with_d(bias))


def pair_dots(k: Jet, pairs) -> Jet:
    """Jets (m,) of the dot products of the static row pairs ((a, b), ...) of k."""
    # Constant one-hot selections (m, 9) instead of gathers: cheaper to compile.
    sel_a = np.eye(9)[[a for a, _ in pairs]]
    sel_b = np.eye(9)[[b for _, b in pairs]]

    def pick(sel, x):
        s = jnp.asarray(sel).reshape(sel.shape + (1,) * (x.ndim - 1))
        return jnp.sum(s * x[None], axis=1)

    a, b = Jet(*(pick(sel_a, x) for x in k)), Jet(*(pick(sel_b, x) for x in k))
    return Jet(
        qt.dot(a.value, b.value),
        jnp.sum(a.jac * b.value[..., None] + b.jac * a.value[..., None], axis=1),
        qt.dot(a.rate, b.value) + qt.dot(a.value, b.rate),
        qt.dot(a.bias, b.value) + 2.0 * qt.dot(a.rate, b.rate)
        + qt.dot(a.value, b.bias),
    )
