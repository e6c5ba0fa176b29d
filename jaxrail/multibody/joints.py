"""Kinematic joints as constraints Phi(q) = 0, with Phi_q, Phidot and gamma.

Each joint connects body i to body j; body index -1 is the ground (the fixed global
frame, whose "body frame" is the global frame, so its points and axes are global).
A joint carries a point and a joint frame on each side: point_i [m] in body i's frame,
frame_i (3, 3) whose columns are the joint's x, y, z axes in body i's frame (same for
j). The joint axis of revolute and prismatic joints is z.

    spherical (3):  r_i + A_i s'_i - r_j - A_j s'_j = 0 (the points coincide)
    revolute  (5):  spherical, and z_i . x_j = z_i . y_j = 0 (z axes parallel)
    fixed     (6):  revolute, and x_i . y_j = 0 (frames aligned)
    prismatic (5):  z_i . x_j = z_i . y_j = x_i . y_j = 0, and d . x_i = d . y_i = 0
                    with d = r_Pj - r_Pi (slides along z_i, no relative rotation)

Phi of one joint is written for one joint, and differentiated by JAX on the 14
coordinates (q_i, q_j) it touches: Phi_q exactly, and gamma = -(Phi_q qdot)_q qdot as
the second directional derivative of Phi along qdot. The same functions are vmapped over
all joints of one kind and scattered into the global matrices with static indices.
The normalisation constraints p_i^T p_i - 1 = 0 (one per body) come first in Phi.
"""

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .bodies import point_position
from .quaternion import rotation_matrix

GROUND = -1
_GROUND_Q = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])


def frame_from_axis(axis, what: str = "axis") -> np.ndarray:
    """A right-handed frame (3, 3) whose z column is the unit `axis` (build time).

    x is the unit cross product of the coordinate axis least aligned with z and z, a
    deterministic choice, so equal axes on both sides of a joint give equal frames.
    """
    z = np.asarray(axis, dtype=np.float64)
    if z.shape != (3,) or not np.all(np.isfinite(z)) or np.linalg.norm(z) == 0.0:
        raise ValueError(f"{what} must be a finite non-zero 3-vector, got {axis!r}")
    z = z / np.linalg.norm(z)
    helper = np.eye(3)[int(np.argmin(np.abs(z)))]
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z], axis=1)


def _check_frame(frame, what):
    f = np.asarray(frame, dtype=np.float64)
    if f.shape != (3, 3) or not np.allclose(f.T @ f, np.eye(3), atol=1e-9):
        raise ValueError(f"{what} must be a (3, 3) rotation matrix")
    if np.linalg.det(f) < 0.0:
        raise ValueError(f"{what} must be right-handed (det = +1)")
    return f


@dataclasses.dataclass(frozen=True)
class _Joint:
    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object

    def frames(self) -> tuple[np.ndarray, np.ndarray]:
        return np.eye(3), np.eye(3)


@dataclasses.dataclass(frozen=True)
class Spherical(_Joint):
    """Spherical joint: point_i [m] of body i and point_j [m] of body j coincide."""

    name: str = ""
    kind: ClassVar[str] = "spherical"


@dataclasses.dataclass(frozen=True)
class Revolute(_Joint):
    """Revolute joint: spherical, plus axis_i of body i parallel to axis_j of body j."""

    axis_i: object = (0.0, 0.0, 1.0)
    axis_j: object = (0.0, 0.0, 1.0)
    name: str = ""
    kind: ClassVar[str] = "revolute"

    def frames(self):
        return frame_from_axis(self.axis_i, "axis_i"), frame_from_axis(
            self.axis_j, "axis_j"
        )


@dataclasses.dataclass(frozen=True)
class Prismatic(_Joint):
    """Prismatic joint: body j slides along axis_i of body i without rotating.

    The relative rotation is locked where the frames `frame_from_axis` builds from
    axis_i and axis_j coincide.
    """

    axis_i: object = (0.0, 0.0, 1.0)
    axis_j: object = (0.0, 0.0, 1.0)
    name: str = ""
    kind: ClassVar[str] = "prismatic"

    def frames(self):
        return frame_from_axis(self.axis_i, "axis_i"), frame_from_axis(
            self.axis_j, "axis_j"
        )


@dataclasses.dataclass(frozen=True)
class Fixed(_Joint):
    """Fixed joint: the points coincide and frame_i (body i) is aligned with frame_j."""

    frame_i: object = None
    frame_j: object = None
    name: str = ""
    kind: ClassVar[str] = "fixed"

    def frames(self):
        fi = np.eye(3) if self.frame_i is None else self.frame_i
        fj = np.eye(3) if self.frame_j is None else self.frame_j
        return _check_frame(fi, "frame_i"), _check_frame(fj, "frame_j")


class JointParams(eqx.Module):
    """Traced geometry of the k joints of one kind.

    Fields:
        point_i, point_j: (k, 3) [m], joint points in the frames of bodies i and j.
        frame_i, frame_j: (k, 3, 3), joint axes (columns x, y, z) in those frames.
    """

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    frame_i: Float[Array, "k 3 3"]
    frame_j: Float[Array, "k 3 3"]


def _sides(qi, qj, jp):
    """Joint points (global) and joint frames (global columns) of both sides."""
    ai = rotation_matrix(qi[3:])
    aj = rotation_matrix(qj[3:])
    pi = point_position(qi[:3], qi[3:], jp.point_i)
    pj = point_position(qj[:3], qj[3:], jp.point_j)
    return pi, pj, ai @ jp.frame_i, aj @ jp.frame_j


def _phi_spherical(qi, qj, jp):
    pi, pj, _, _ = _sides(qi, qj, jp)
    return pi - pj


def _phi_revolute(qi, qj, jp):
    pi, pj, fi, fj = _sides(qi, qj, jp)
    zi = fi[:, 2]
    return jnp.concatenate([pi - pj, jnp.stack([zi @ fj[:, 0], zi @ fj[:, 1]])])


def _phi_fixed(qi, qj, jp):
    pi, pj, fi, fj = _sides(qi, qj, jp)
    zi = fi[:, 2]
    dots = jnp.stack([zi @ fj[:, 0], zi @ fj[:, 1], fi[:, 0] @ fj[:, 1]])
    return jnp.concatenate([pi - pj, dots])


def _phi_prismatic(qi, qj, jp):
    pi, pj, fi, fj = _sides(qi, qj, jp)
    zi = fi[:, 2]
    d = pj - pi
    return jnp.stack(
        [zi @ fj[:, 0], zi @ fj[:, 1], fi[:, 0] @ fj[:, 1], d @ fi[:, 0], d @ fi[:, 1]]
    )


# kind -> (number of equations, Phi of one joint)
JOINT_KINDS = {
    "spherical": (3, _phi_spherical),
    "revolute": (5, _phi_revolute),
    "fixed": (6, _phi_fixed),
    "prismatic": (5, _phi_prismatic),
}


def joint_phi(kind: str, qi, qj, jp) -> Array:
    """Phi (neq,) of one joint of `kind` from q_i (7,), q_j (7,) and its JointParams
    (unbatched)."""
    return JOINT_KINDS[kind][1](qi, qj, jp)


def _one_joint(kind, qi, qj, vi, vj, jp):
    """Phi, dPhi/dq_i, dPhi/dq_j, Phidot and gamma of one joint."""
    phi_fn = JOINT_KINDS[kind][1]
    phi = phi_fn(qi, qj, jp)
    jac_i, jac_j = jax.jacfwd(phi_fn, argnums=(0, 1))(qi, qj, jp)

    def along(s):  # Phi on the straight line q + s qdot
        return phi_fn(qi + s * vi, qj + s * vj, jp)

    def rate(s):
        return jax.jvp(along, (s,), (jnp.ones_like(s),))[1]

    zero = jnp.zeros((), dtype=qi.dtype)
    phidot, second = jax.jvp(rate, (zero,), (jnp.ones_like(zero),))
    return phi, jac_i, jac_j, phidot, -second


def ground_extended(x):
    """Append the ground's coordinates (origin, identity) as row n of x (n, 7)."""
    return jnp.concatenate([x, jnp.asarray(_GROUND_Q, dtype=x.dtype)[None]], axis=0)


def joint_terms(kind: str, body_i, body_j, jp: JointParams, q, qdot):
    """Phi, Phi_q, Phidot, gamma of the k joints of one kind (stacked, joint-major).

    Arguments:
        kind: a key of JOINT_KINDS (static).
        body_i, body_j: static int sequences (k,), body indices, -1 for ground.
        jp: JointParams with leading axis k.
        q, qdot: (7 n,) system coordinates and their time derivatives.

    Returns (phi (k neq,), phi_q (k neq, 7 n), phidot (k neq,), gamma (k neq,)).
    """
    neq = JOINT_KINDS[kind][0]
    n = q.shape[0] // 7
    bi = np.asarray(body_i, dtype=np.int64)
    bj = np.asarray(body_j, dtype=np.int64)
    k = bi.shape[0]
    q_ext = ground_extended(q.reshape(n, 7))
    v_ext = jnp.concatenate([qdot.reshape(n, 7), jnp.zeros((1, 7))], axis=0)
    # Index -1 picks the appended ground row.
    phi, jac_i, jac_j, phidot, gamma = jax.vmap(
        lambda qi, qj, vi, vj, p: _one_joint(kind, qi, qj, vi, vj, p)
    )(q_ext[bi], q_ext[bj], v_ext[bi], v_ext[bj], jp)
    rows = np.arange(k * neq).reshape(k, neq, 1)
    cols_i = (7 * np.where(bi < 0, n, bi))[:, None, None] + np.arange(7)
    cols_j = (7 * np.where(bj < 0, n, bj))[:, None, None] + np.arange(7)
    phi_q = jnp.zeros((k * neq, 7 * (n + 1)), dtype=q.dtype)
    phi_q = phi_q.at[rows, cols_i].add(jac_i).at[rows, cols_j].add(jac_j)
    return phi.reshape(-1), phi_q[:, : 7 * n], phidot.reshape(-1), gamma.reshape(-1)


def normalization_terms(q, qdot):
    """Phi = p^T p - 1 per body, Phi_q = 2 p^T, Phidot, gamma = -2 pdot^T pdot."""
    n = q.shape[0] // 7
    p = q.reshape(n, 7)[:, 3:]
    pdot = qdot.reshape(n, 7)[:, 3:]
    phi = jnp.sum(p * p, axis=1) - 1.0
    rows = np.arange(n)[:, None]
    cols = 7 * np.arange(n)[:, None] + 3 + np.arange(4)
    phi_q = jnp.zeros((n, 7 * n), dtype=q.dtype).at[rows, cols].set(2.0 * p)
    phidot = 2.0 * jnp.sum(p * pdot, axis=1)
    gamma = -2.0 * jnp.sum(pdot * pdot, axis=1)
    return phi, phi_q, phidot, gamma
