"""Force elements and generalized forces in the Euler-parameter (pdot) convention.

A force f (global, [N]) at the body point s' [m] (body frame) and a torque n (global,
[N m]) on body i do the virtual work f . delta r_P + n . delta pi, which in the
coordinates q_i = (r, p) is the generalized force

    g_r = f,     g_p = 2 G^T n',     n' = s' x (A^T f) + A^T n   (body frame).

Suspension elements (spring-dampers, bushings, bump stops) between body i and body j
(-1 for the ground) are written as a few deformation coordinates s(q_i, q_j) and a
law F(s, sdot) giving the generalised force -(ds/dq)^T F. The stiffness part is then
exactly minus the gradient of the element's potential, so conservative systems keep
their energy. The component of g_p along p does no work on the unit sphere (it only
changes the normalisation multiplier) and is removed, so every g_p here is tangent.

Kinds and deformation coordinates (points and axes in the frames of their bodies):

    spring_damper (1): length L = |r_Pj - r_Pi|;  F = k (L - L0) + c Ldot.
    bushing (6):       u = B_i^T (r_Pj - r_Pi) and theta = vee(skew part of B_i^T B_j),
                       B = A frame (bushing axes in global); theta is the small-angle
                       rotation of frame j relative to frame i (sin of the angle about
                       one axis); F = K s + C sdot + F0 (six values each, diagonal).
    bump_stop (1):     s = a_i . (r_Pj - r_Pi), a_i = A_i axis_i; acts once s exceeds
                       the clearance: F = max(k (s - c) + d sdot, 0) for s > c, else 0.
"""

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import quaternion as qt
from .bodies import point_position
from .joints import ground_extended


def _tangent(p, g_p):
    """Remove the component of g_p along p (it does no work while |p| = 1)."""
    return g_p - p * (p @ g_p) / (p @ p)


def point_force(p, point, force) -> Float[Array, " 7"]:
    """Generalized force (7,) of a global force [N] at body point `point` [m] (body
    frame) of a body with Euler parameters p: (f, 2 G^T (s' x A^T f))."""
    a = qt.rotation_matrix(p)
    n_body = jnp.cross(point, a.T @ force)
    return jnp.concatenate([force, 2.0 * qt.g_matrix(p).T @ n_body])


def body_torque(p, torque) -> Float[Array, " 7"]:
    """Generalized force (7,) of a global torque [N m] on a body: (0, 2 G^T A^T n)."""
    n_body = qt.rotation_matrix(p).T @ torque
    return jnp.concatenate([jnp.zeros(3), 2.0 * qt.g_matrix(p).T @ n_body])


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


# ---- build-time descriptions ----------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class SpringDamper:
    """Linear spring-damper between point_i of body i and point_j of body j.

    stiffness k [N/m], free_length L0 [m], damping c [N s/m]. Tension positive.
    """

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    stiffness: float
    free_length: float
    damping: float = 0.0
    name: str = ""
    kind: ClassVar[str] = "spring_damper"


@dataclasses.dataclass(frozen=True)
class Bushing:
    """Six-component linear bushing between body i and body j.

    The bushing frame is frame_i (columns = axes, in body i's frame) at point_i; on
    body j it is frame_j at point_j; at zero deflection both coincide. stiffness (6,):
    (kx, ky, kz [N/m], krx, kry, krz [N m/rad]); damping (6,) in [N s/m] and
    [N m s/rad]; preload (6,) [N, N m]: force the element carries at zero deflection,
    same sign as K s (positive pulls body j back towards -axis).
    """

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    stiffness: object
    damping: object = (0.0,) * 6
    frame_i: object = None
    frame_j: object = None
    preload: object = (0.0,) * 6
    name: str = ""
    kind: ClassVar[str] = "bushing"


@dataclasses.dataclass(frozen=True)
class BumpStop:
    """One-sided spring with clearance: pushes point_j back once it has moved more
    than `clearance` [m] beyond point_i along axis_i (body i frame, normalised).

    stiffness [N/m], damping [N s/m] (only while in contact; the force never pulls).
    """

    body_i: int | str
    body_j: int | str
    point_i: object
    point_j: object
    axis_i: object
    clearance: float
    stiffness: float
    damping: float = 0.0
    name: str = ""
    kind: ClassVar[str] = "bump_stop"


# ---- traced parameters ------------------------------------------------------------


class SpringDamperParams(eqx.Module):
    """(k, 3) points [m]; (k,) stiffness [N/m], damping [N s/m], free_length [m]."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    stiffness: Float[Array, " k"]
    damping: Float[Array, " k"]
    free_length: Float[Array, " k"]


class BushingParams(eqx.Module):
    """(k, 3) points [m]; (k, 3, 3) frames; (k, 6) stiffness, damping, preload."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    frame_i: Float[Array, "k 3 3"]
    frame_j: Float[Array, "k 3 3"]
    stiffness: Float[Array, "k 6"]
    damping: Float[Array, "k 6"]
    preload: Float[Array, "k 6"]


class BumpStopParams(eqx.Module):
    """(k, 3) points [m] and axis; (k,) clearance [m], stiffness, damping."""

    point_i: Float[Array, "k 3"]
    point_j: Float[Array, "k 3"]
    axis_i: Float[Array, "k 3"]
    clearance: Float[Array, " k"]
    stiffness: Float[Array, " k"]
    damping: Float[Array, " k"]


# ---- one element: deformation coordinates, law, potential -------------------------------


def _points(qi, qj, e):
    return (
        point_position(qi[:3], qi[3:], e.point_i),
        point_position(qj[:3], qj[3:], e.point_j),
    )


def _spring_coords(qi, qj, e):
    pi, pj = _points(qi, qj, e)
    d2 = jnp.sum((pj - pi) ** 2)
    safe = jnp.where(d2 > 0.0, d2, 1.0)
    return jnp.where(d2 > 0.0, jnp.sqrt(safe), 0.0)[None]


def _spring_law(s, sdot, e):
    return e.stiffness * (s - e.free_length) + e.damping * sdot


def _spring_potential(s, e):
    return 0.5 * e.stiffness * jnp.sum((s - e.free_length) ** 2)


def _bushing_coords(qi, qj, e):
    pi, pj = _points(qi, qj, e)
    bi = qt.rotation_matrix(qi[3:]) @ e.frame_i
    bj = qt.rotation_matrix(qj[3:]) @ e.frame_j
    return jnp.concatenate([bi.T @ (pj - pi), qt.vee(bi.T @ bj)])


def _bushing_law(s, sdot, e):
    return e.stiffness * s + e.damping * sdot + e.preload


def _bushing_potential(s, e):
    return jnp.sum(0.5 * e.stiffness * s**2 + e.preload * s)


def _bump_coords(qi, qj, e):
    pi, pj = _points(qi, qj, e)
    axis = qt.rotation_matrix(qi[3:]) @ e.axis_i
    return (axis @ (pj - pi) / jnp.linalg.norm(e.axis_i))[None]


def _bump_law(s, sdot, e):
    gap = s - e.clearance
    push = jnp.maximum(e.stiffness * gap + e.damping * sdot, 0.0)
    return jnp.where(gap > 0.0, push, 0.0)


def _bump_potential(s, e):
    return 0.5 * e.stiffness * jnp.sum(jnp.maximum(s - e.clearance, 0.0) ** 2)


# kind -> (coordinates, law, potential)
FORCE_KINDS = {
    "spring_damper": (_spring_coords, _spring_law, _spring_potential),
    "bushing": (_bushing_coords, _bushing_law, _bushing_potential),
    "bump_stop": (_bump_coords, _bump_law, _bump_potential),
}


def element_deformation(kind: str, qi, qj, e) -> Array:
    """Deformation coordinates s of one element of `kind` (see module docstring)."""
    return FORCE_KINDS[kind][0](qi, qj, e)


def _one_element(kind, qi, qj, vi, vj, e):
    coords, law, _ = FORCE_KINDS[kind]
    s = coords(qi, qj, e)
    jac_i, jac_j = jax.jacfwd(coords, argnums=(0, 1))(qi, qj, e)
    sdot = jac_i @ vi + jac_j @ vj
    f = law(s, sdot, e)
    gi, gj = -jac_i.T @ f, -jac_j.T @ f
    gi = gi.at[3:].set(_tangent(qi[3:], gi[3:]))
    gj = gj.at[3:].set(_tangent(qj[3:], gj[3:]))
    return gi, gj


def element_forces(kind: str, body_i, body_j, e, q, qdot) -> Float[Array, " 7n"]:
    """Summed generalized forces (7 n,) of the k elements of one kind.

    body_i, body_j: static int sequences (k,), -1 for ground; e: the kind's params
    with leading axis k; q, qdot (7 n,).
    """
    n = q.shape[0] // 7
    bi = np.asarray(body_i, dtype=np.int64)
    bj = np.asarray(body_j, dtype=np.int64)
    q_ext = ground_extended(q.reshape(n, 7))
    v_ext = jnp.concatenate([qdot.reshape(n, 7), jnp.zeros((1, 7))], axis=0)
    gi, gj = jax.vmap(lambda a, b, c, d, p: _one_element(kind, a, b, c, d, p))(
        q_ext[bi], q_ext[bj], v_ext[bi], v_ext[bj], e
    )
    g = jnp.zeros((n + 1, 7), dtype=q.dtype)
    g = g.at[np.where(bi < 0, n, bi)].add(gi).at[np.where(bj < 0, n, bj)].add(gj)
    return g[:n].reshape(-1)


def element_potential(kind: str, body_i, body_j, e, q) -> Float[Array, ""]:
    """Summed stored energy [J] of the k elements of one kind (dampers excluded)."""
    n = q.shape[0] // 7
    coords, _, potential = FORCE_KINDS[kind]
    q_ext = ground_extended(q.reshape(n, 7))
    bi = np.asarray(body_i, dtype=np.int64)
    bj = np.asarray(body_j, dtype=np.int64)
    v = jax.vmap(lambda a, b, p: potential(coords(a, b, p), p))(q_ext[bi], q_ext[bj], e)
    return jnp.sum(v)
