"""Euler parameters (unit quaternions) in Nikravesh's convention.

An orientation is p = (e0, e1, e2, e3) = (cos(phi/2), sin(phi/2) u) for a rotation by
phi [rad] about the unit axis u, scalar part **first**. The rotation matrix A(p) maps
body-frame components to global ones: x_global = A x_body. With e = (e1, e2, e3)

    A = (2 e0^2 - 1) I + 2 (e e^T + e0 e~),      e~ = skew(e),
    E = [-e, e~ + e0 I],   G = [-e, -e~ + e0 I]   (3 x 4 each),   A = E G^T,
    omega = 2 E pdot (global frame),   omega' = 2 G pdot (body frame),
    pdot = 1/2 E^T omega = 1/2 G^T omega'   (for |p| = 1).

G and E are linear in p and G(p) p = E(p) p = 0, so G(pdot) pdot = 0 as well.
All functions take and return float64 arrays and work under jit, vmap and grad.
"""

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._float64 import f64


# Small-array products written as broadcast-multiply-and-sum: XLA on CPU compiles a
# tiny dot_general roughly ten times slower than the equivalent elementwise ops, and a
# multibody right-hand side has hundreds of them.
def dot(a, b):
    """Sum over the last axis of a * b (vector dot product, broadcasting)."""
    return jnp.sum(a * b, axis=-1)


def matvec(a, x):
    """a (..., m, k) times x (..., k) -> (..., m)."""
    return jnp.sum(a * x[..., None, :], axis=-1)


def matmul(a, b):
    """a (..., m, k) times b (..., k, l) -> (..., m, l)."""
    return jnp.sum(a[..., :, :, None] * b[..., None, :, :], axis=-2)


# Constant tensors: skew, G, E and A are (bi)linear maps of their arguments, and
# contracting with a constant tensor keeps the traced graph (and compile time) small.
_LEVI = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    _LEVI[_i, _j, _k], _LEVI[_i, _k, _j] = 1.0, -1.0


def _skew_np(v):
    return -np.einsum("ijk,k->ij", _LEVI, v)


def _g_np(p):
    return np.concatenate([-p[1:, None], -_skew_np(p[1:]) + p[0] * np.eye(3)], axis=1)


def _e_np(p):
    return np.concatenate([-p[1:, None], _skew_np(p[1:]) + p[0] * np.eye(3)], axis=1)


def _quadratic_a_np(p, r):
    """Symmetric bilinear form with A(p) = Q(p, p) - I: Q(p, p) = 2 e0^2 I + 2 e e^T
    + 2 e0 e~."""
    e0, e, f0, f = p[0], p[1:], r[0], r[1:]
    return (2.0 * e0 * f0 * np.eye(3) + np.outer(e, f) + np.outer(f, e)
            + e0 * _skew_np(f) + f0 * _skew_np(e))


_BASIS = np.eye(4)
_G_TENSOR = np.stack([_g_np(b) for b in _BASIS], axis=-1)  # (3, 4, 4)
_E_TENSOR = np.stack([_e_np(b) for b in _BASIS], axis=-1)  # (3, 4, 4)
_A_TENSOR = np.stack(  # (3, 3, 4, 4)
    [np.stack([_quadratic_a_np(b, c) for c in _BASIS], axis=-1) for b in _BASIS],
    axis=-2,
)


def skew(v: Float[ArrayLike, "3"]) -> Float[Array, "3 3"]:
    """The cross-product matrix v~, with v~ w = v x w."""
    return -matvec(jnp.asarray(_LEVI), f64(v))


def vee(m: Float[ArrayLike, "3 3"]) -> Float[Array, "3"]:
    """Inverse of `skew` applied to the skew-symmetric part of m."""
    return -0.5 * jnp.sum(jnp.asarray(_LEVI) * f64(m)[:, :, None], axis=(0, 1))


def rotation_matrix(p: Float[ArrayLike, "4"]) -> Float[Array, "3 3"]:
    """A(p): body-to-global rotation matrix (3, 3); orthogonal only if |p| = 1.

    Written entry by entry (the same quadratic form as Q(p, p) - I, a tenth of the
    products of contracting `_A_TENSOR`)."""
    e0, e1, e2, e3 = jnp.moveaxis(f64(p), -1, 0)
    d = 2.0 * e0 * e0 - 1.0
    rows = (
        (d + 2.0 * e1 * e1, 2.0 * (e1 * e2 - e0 * e3), 2.0 * (e1 * e3 + e0 * e2)),
        (2.0 * (e1 * e2 + e0 * e3), d + 2.0 * e2 * e2, 2.0 * (e2 * e3 - e0 * e1)),
        (2.0 * (e1 * e3 - e0 * e2), 2.0 * (e2 * e3 + e0 * e1), d + 2.0 * e3 * e3),
    )
    return jnp.stack([jnp.stack(r, axis=-1) for r in rows], axis=-2)


def rotation_matrix_rate(
    p: Float[ArrayLike, "4"], pdot: Float[ArrayLike, "4"]
) -> Float[Array, "3 3"]:
    """dA/dt (3, 3) = 2 Q(p, pdot): the exact derivative of A(p) along pdot."""
    return 2.0 * matvec(matvec(jnp.asarray(_A_TENSOR), f64(pdot)), f64(p))


def rotation_tensor(p: Float[ArrayLike, "4"]) -> Float[Array, "3 3 4"]:
    """M(p) (3, 3, 4), linear in p, with A(p) = M(p) p - I and dA/dp = 2 M(p).

    Hence dA/dt = 2 M(p) pdot, and the second derivative of A along pdot (with
    pddot = 0) is 2 M(pdot) pdot: everything the joint and force kinematics need.
    """
    return matvec(jnp.asarray(_A_TENSOR), f64(p))


def g_matrix(p: Float[ArrayLike, "4"]) -> Float[Array, "3 4"]:
    """Nikravesh's G(p) (3, 4): omega' = 2 G pdot (body frame)."""
    e0, e1, e2, e3 = jnp.moveaxis(f64(p), -1, 0)
    rows = ((-e1, e0, e3, -e2), (-e2, -e3, e0, e1), (-e3, e2, -e1, e0))
    return jnp.stack([jnp.stack(r, axis=-1) for r in rows], axis=-2)


def e_matrix(p: Float[ArrayLike, "4"]) -> Float[Array, "3 4"]:
    """Nikravesh's E(p) (3, 4): omega = 2 E pdot (global frame)."""
    return matvec(jnp.asarray(_E_TENSOR), f64(p))


def normalize(p: Float[ArrayLike, "4"]) -> Float[Array, "4"]:
    """p / |p| (p must not be zero)."""
    p = f64(p)
    return p / jnp.linalg.norm(p)


def from_axis_angle(
    axis: Float[ArrayLike, "3"], angle: Float[ArrayLike, ""]
) -> Float[Array, "4"]:
    """Euler parameters of a rotation by `angle` [rad] about `axis` (normalised here).

    The right-hand rule: a positive angle turns counter-clockwise seen from the tip of
    `axis`.
    """
    axis = f64(axis)
    half = 0.5 * f64(angle)
    u = axis / jnp.linalg.norm(axis)
    return jnp.concatenate([jnp.cos(half)[None], jnp.sin(half) * u])


def from_rotation_matrix(a: Float[ArrayLike, "3 3"]) -> Float[Array, "4"]:
    """Euler parameters (e0 >= 0 where possible) of a rotation matrix (Shepperd).

    All four candidate formulas are evaluated and the best-conditioned one selected,
    so the function is jit-able and its gradient finite for every rotation.
    """
    a = f64(a)
    tr = jnp.trace(a)
    diag = jnp.diagonal(a)
    # 4 * (squared component) for the candidate pivots e0, e1, e2, e3.
    four_sq = jnp.array(
        [
            1.0 + tr,
            1.0 + 2.0 * diag[0] - tr,
            1.0 + 2.0 * diag[1] - tr,
            1.0 + 2.0 * diag[2] - tr,
        ]
    )
    k = jnp.argmax(four_sq)
    safe = jnp.where(four_sq > 1e-300, four_sq, 1.0)
    s = jnp.sqrt(safe)  # 2 * |pivot component|
    w1 = a[2, 1] - a[1, 2]
    w2 = a[0, 2] - a[2, 0]
    w3 = a[1, 0] - a[0, 1]
    s01 = a[0, 1] + a[1, 0]
    s02 = a[0, 2] + a[2, 0]
    s12 = a[1, 2] + a[2, 1]
    h = 0.5 * s  # the pivot component
    q = 0.5 / s  # the others are (sums or differences of A) / (4 * pivot)
    cands = jnp.array(
        [
            [h[0], w1 * q[0], w2 * q[0], w3 * q[0]],
            [w1 * q[1], h[1], s01 * q[1], s02 * q[1]],
            [w2 * q[2], s01 * q[2], h[2], s12 * q[2]],
            [w3 * q[3], s02 * q[3], s12 * q[3], h[3]],
        ]
    )
    p = cands[k]
    # The rotation fixes p only up to sign: prefer e0 >= 0.
    return jnp.where(p[0] < 0.0, -p, p)


def multiply(p: Float[ArrayLike, "4"], r: Float[ArrayLike, "4"]) -> Float[Array, "4"]:
    """Quaternion product p * r, with A(p * r) = A(p) A(r)."""
    p, r = f64(p), f64(r)
    p0, pv = p[0], p[1:]
    r0, rv = r[0], r[1:]
    return jnp.concatenate(
        [(p0 * r0 - dot(pv, rv))[None], p0 * rv + r0 * pv + jnp.cross(pv, rv)]
    )


def pdot_from_omega_global(
    p: Float[ArrayLike, "4"], omega: Float[ArrayLike, "3"]
) -> Float[Array, "4"]:
    """pdot [1/s] (4,) of a unit p rotating at omega [rad/s] in the global frame."""
    return 0.5 * matvec(e_matrix(p).T, f64(omega))


def pdot_from_omega_body(
    p: Float[ArrayLike, "4"], omega_body: Float[ArrayLike, "3"]
) -> Float[Array, "4"]:
    """pdot [1/s] (4,) of a unit p rotating at omega' [rad/s] in the body frame."""
    return 0.5 * matvec(g_matrix(p).T, f64(omega_body))
