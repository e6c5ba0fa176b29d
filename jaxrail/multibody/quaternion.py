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
from jaxtyping import Array, ArrayLike, Float


def _f64(x):
    return jnp.asarray(x, dtype=jnp.float64)


def skew(v: Float[ArrayLike, "3"]) -> Float[Array, "3 3"]:
    """The cross-product matrix v~, with v~ w = v x w."""
    v = _f64(v)
    z = jnp.zeros((), dtype=v.dtype)
    return jnp.array(
        [[z, -v[2], v[1]], [v[2], z, -v[0]], [-v[1], v[0], z]], dtype=v.dtype
    )


def vee(m: Float[ArrayLike, "3 3"]) -> Float[Array, "3"]:
    """Inverse of `skew` applied to the skew-symmetric part of m."""
    m = _f64(m)
    return 0.5 * jnp.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])


def rotation_matrix(p: Float[ArrayLike, "4"]) -> Float[Array, "3 3"]:
    """A(p): body-to-global rotation matrix (3, 3); orthogonal only if |p| = 1."""
    p = _f64(p)
    e0, e = p[0], p[1:]
    eye = jnp.eye(3, dtype=p.dtype)
    return (2.0 * e0**2 - 1.0) * eye + 2.0 * (jnp.outer(e, e) + e0 * skew(e))


def g_matrix(p: Float[ArrayLike, "4"]) -> Float[Array, "3 4"]:
    """Nikravesh's G(p) (3, 4): omega' = 2 G pdot (body frame)."""
    p = _f64(p)
    e0, e = p[0], p[1:]
    return jnp.concatenate([-e[:, None], -skew(e) + e0 * jnp.eye(3)], axis=1)


def e_matrix(p: Float[ArrayLike, "4"]) -> Float[Array, "3 4"]:
    """Nikravesh's E(p) (3, 4): omega = 2 E pdot (global frame)."""
    p = _f64(p)
    e0, e = p[0], p[1:]
    return jnp.concatenate([-e[:, None], skew(e) + e0 * jnp.eye(3)], axis=1)


def normalize(p: Float[ArrayLike, "4"]) -> Float[Array, "4"]:
    """p / |p| (p must not be zero)."""
    p = _f64(p)
    return p / jnp.linalg.norm(p)


def from_axis_angle(
    axis: Float[ArrayLike, "3"], angle: Float[ArrayLike, ""]
) -> Float[Array, "4"]:
    """Euler parameters of a rotation by `angle` [rad] about `axis` (normalised here).

    The right-hand rule: a positive angle turns counter-clockwise seen from the tip of
    `axis`.
    """
    axis = _f64(axis)
    half = 0.5 * _f64(angle)
    u = axis / jnp.linalg.norm(axis)
    return jnp.concatenate([jnp.cos(half)[None], jnp.sin(half) * u])


def from_rotation_matrix(a: Float[ArrayLike, "3 3"]) -> Float[Array, "4"]:
    """Euler parameters (e0 >= 0 where possible) of a rotation matrix (Shepperd).

    All four candidate formulas are evaluated and the best-conditioned one selected,
    so the function is jit-able and its gradient finite for every rotation.
    """
    a = _f64(a)
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
    p, r = _f64(p), _f64(r)
    p0, pv = p[0], p[1:]
    r0, rv = r[0], r[1:]
    return jnp.concatenate(
        [(p0 * r0 - pv @ rv)[None], p0 * rv + r0 * pv + jnp.cross(pv, rv)]
    )


def pdot_from_omega_global(
    p: Float[ArrayLike, "4"], omega: Float[ArrayLike, "3"]
) -> Float[Array, "4"]:
    """pdot [1/s] (4,) of a unit p rotating at omega [rad/s] in the global frame."""
    return 0.5 * e_matrix(p).T @ _f64(omega)


def pdot_from_omega_body(
    p: Float[ArrayLike, "4"], omega_body: Float[ArrayLike, "3"]
) -> Float[Array, "4"]:
    """pdot [1/s] (4,) of a unit p rotating at omega' [rad/s] in the body frame."""
    return 0.5 * g_matrix(p).T @ _f64(omega_body)
