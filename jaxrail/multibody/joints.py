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

Each equation is built from body points and body axes and their dot products as a
`Jet` (bodies.pair_kinematics): value, Jacobian over the 14 coordinates (q_i, q_j),
rate, and the bias (Phi_q qdot)_q qdot, all analytic (A(p) is quadratic in p), so
gamma = -bias (`joint_jet`; tests check them against jax.jacfwd and finite differences).
`joint_terms`, on the right-hand side, differentiates the plain `joint_phi` by AD
instead (fewer operations than the 14-column Jets). One joint is written once,
vmapped over all joints of a kind, its bodies' coordinates taken as constant slices
and its Jacobian placed into the global matrices with constant one-hot products. The
normalisation constraints p_i^T p_i - 1 = 0 (one per body) come first in Phi.
"""

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..compilation import traced_once
from . import quaternion as qt
from ._values import checked_axis
from .bodies import D, X_I, X_J, Y_I, Y_J, Z_I, Jet, pair_dots, pair_kinematics

GROUND = -1
_GROUND_Q = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])


def frame_from_axis(axis, what: str = "axis") -> np.ndarray:
    """A right-handed frame (3, 3) whose z column is the unit `axis` (build time).

    x is the unit cross product of the coordinate axis least aligned with z and z, a
    deterministic choice, so equal axes on both sides of a joint give equal frames.
    """
    z = checked_axis(axis, what)
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


# kind -> (number of equations, points coincide?, dot products that vanish). Rows of
# bodies.pair_kinematics: X_I etc. are the joint axes, D = r_Pj - r_Pi.
_PARALLEL = ((Z_I, X_J), (Z_I, Y_J))
JOINT_KINDS = {
    "spherical": (3, True, ()),
    "revolute": (5, True, _PARALLEL),
    "fixed": (6, True, _PARALLEL + ((X_I, Y_J),)),
    "prismatic": (5, False, _PARALLEL + ((X_I, Y_J), (D, X_I), (D, Y_I))),
}


def joint_jet(kind: str, qi, qj, vi, vj, jp) -> Jet:
    """Phi (neq,), Phi_q (neq, 14) over (q_i, q_j), Phidot and bias = -gamma of one
    joint of `kind` (unbatched JointParams) at q_i, q_j (7,) moving at v_i, v_j (7,).
    """
    _, coincide, pairs = JOINT_KINDS[kind]
    k = pair_kinematics(qi, qj, vi, vj, jp.point_i, jp.frame_i.T, jp.point_j,
                        jp.frame_j.T)
    parts = []
    if coincide:  # r_Pi - r_Pj = -D
        parts.append(Jet(*(-x[D] for x in k)))
    if pairs:
        parts.append(pair_dots(k, pairs))
    return Jet(*(jnp.concatenate(xs, axis=0) for xs in zip(*parts)))


def joint_phi(kind: str, qi, qj, jp) -> Array:
    """Phi (neq,) of one joint of `kind` from q_i (7,), q_j (7,) (unbatched params).

    Written directly from the two bodies' points and axes (the same equations as
    `joint_jet`, without its Jacobian): `joint_terms` differentiates it.
    """
    _, coincide, pairs = JOINT_KINDS[kind]
    a_i, a_j = qt.rotation_matrix(qi[3:]), qt.rotation_matrix(qj[3:])
    d = qj[:3] + qt.matvec(a_j, jp.point_j) - qi[:3] - qt.matvec(a_i, jp.point_i)
    axes_i = qt.matmul(a_i, jp.frame_i)  # columns: the joint axes, global
    axes_j = qt.matmul(a_j, jp.frame_j)
    rows = {X_I: axes_i[:, 0], Y_I: axes_i[:, 1], Z_I: axes_i[:, 2],
            X_J: axes_j[:, 0], Y_J: axes_j[:, 1], D: d}
    parts = [-d] if coincide else []
    if pairs:
        parts.append(jnp.stack([qt.dot(rows[a], rows[b]) for a, b in pairs]))
    return jnp.concatenate(parts)


def _joint_terms_one(kind, qi, qj, vi, vj, jp):
    """(Phi, Phi_q (neq, 14), Phidot, gamma) of one joint, by AD of `joint_phi`:
    Phi_q by forward mode, gamma = -(Phi_q qdot)_q qdot as the second derivative
    of Phi along qdot."""
    x, v = jnp.concatenate([qi, qj]), jnp.concatenate([vi, vj])

    def phi(x):
        return joint_phi(kind, x[:7], x[7:], jp)

    def phidot(x):
        return jax.jvp(phi, (x,), (v,))

    (value, rate), (_, bias) = jax.jvp(phidot, (x,), (v,))
    return value, jax.jacfwd(phi)(x), rate, -bias


def ground_extended(x):
    """Append the ground's coordinates (origin, identity) as row n of x (n, 7)."""
    return jnp.concatenate([x, jnp.asarray(_GROUND_Q, dtype=x.dtype)[None]], axis=0)


def body_selector(body, n: int) -> Array:
    """One-hot (k, n + 1) of static body indices (-1, the ground, is column n).

    Selecting and scattering with constant one-hot products instead of gathers and
    scatters keeps the compiled graph small (and the same for forward and reverse AD).
    """
    b = np.asarray(body, dtype=np.int64)
    return jnp.asarray(np.eye(n + 1)[np.where(b < 0, n, b)])


def body_rows(body, x_ext) -> Array:
    """Rows (k, ...) of x_ext (n + 1, ...) of static body indices ``body`` (k,) (-1, the
    ground, is row n): constant slices, stacked (a one-hot product would multiply every
    row; a gather would make reverse mode scatter)."""
    n = x_ext.shape[0] - 1
    return jnp.stack([x_ext[n if b < 0 else b] for b in body])


def body_sums(body, blocks, n: int) -> Array:
    """(n, ...): per body, the sum of the blocks (k, ...) whose static body index
    ``body`` (k,) is that body's (the ground's, -1, dropped); constant slices added."""
    zero = jnp.zeros(blocks.shape[1:], blocks.dtype)
    return jnp.stack([sum((blocks[k] for k, b in enumerate(body) if b == i), zero)
                      for i in range(n)])


def place_bodies(selector, blocks) -> Array:
    """(k, ..., n + 1, 7): blocks (k, ..., 7) put in the column block of each body."""
    s = selector.reshape(selector.shape[:1] + (1,) * (blocks.ndim - 2)
                         + selector.shape[1:] + (1,))
    return s * blocks[..., None, :]


@traced_once
def joint_terms(kind: str, body_i, body_j, jp: JointParams, q, qdot):
    """Phi, Phi_q, Phidot, gamma of the k joints of one kind (stacked, joint-major).

    Arguments:
        kind: a key of JOINT_KINDS (static).
        body_i, body_j: static int sequences (k,), body indices, -1 for ground.
        jp: JointParams with leading axis k.
        q, qdot: (7 n,) system coordinates and their time derivatives.

    Returns (phi (k neq,), phi_q (k neq, 7 n), phidot (k neq,), gamma (k neq,)).
    """
    n = q.shape[0] // 7
    sel_i, sel_j = body_selector(body_i, n), body_selector(body_j, n)
    q_ext = ground_extended(q.reshape(n, 7))
    v_ext = jnp.concatenate([qdot.reshape(n, 7), jnp.zeros((1, 7))], axis=0)
    value, jac, rate, gamma = jax.vmap(
        lambda qi, qj, vi, vj, p: _joint_terms_one(kind, qi, qj, vi, vj, p))(
        body_rows(body_i, q_ext), body_rows(body_j, q_ext),
        body_rows(body_i, v_ext), body_rows(body_j, v_ext), jp,
    )
    phi_q = place_bodies(sel_i, jac[..., :7]) + place_bodies(sel_j, jac[..., 7:])
    k, neq = value.shape
    phi_q = phi_q[:, :, :n, :].reshape(k * neq, 7 * n)  # the ground's columns dropped
    return value.reshape(-1), phi_q, rate.reshape(-1), gamma.reshape(-1)


def normalization_terms(q, qdot):
    """Phi = p^T p - 1 per body, Phi_q = 2 p^T, Phidot, gamma = -2 pdot^T pdot."""
    n = q.shape[0] // 7
    p = q.reshape(n, 7)[:, 3:]
    pdot = qdot.reshape(n, 7)[:, 3:]
    phi = jnp.sum(p * p, axis=1) - 1.0
    row = jnp.concatenate([jnp.zeros((n, 3), dtype=q.dtype), 2.0 * p], axis=1)
    phi_q = (jnp.eye(n)[:, :, None] * row[:, None, :]).reshape(n, 7 * n)
    phidot = 2.0 * jnp.sum(p * pdot, axis=1)
    gamma = -2.0 * jnp.sum(pdot * pdot, axis=1)
    return phi, phi_q, phidot, gamma
