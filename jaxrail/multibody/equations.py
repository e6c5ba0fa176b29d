"""The equations of motion of a multibody system, eq. (19), assembled and solved.

Equations of motion (Nikravesh; the paper's eq. 19 with Baumgarte stabilisation):

    [ M     Phi_q^T ] [ qddot  ]   [ g + h                              ]
    [ Phi_q 0       ] [ lambda ] = [ gamma - 2 alpha Phidot - beta^2 Phi ]

with M = blockdiag(m_i I3, 4 G_i^T J'_i G_i), g the applied generalized forces
(gravity, force elements, the `external` hook), h the quadratic velocity vector and
Phi the normalisation constraints followed by the joints. Sign of lambda: the joint
reactions on the bodies are -Phi_q^T lambda (for a spherical joint, -lambda is the
force [N] on body i and +lambda the force on body j, global frame).
"""

import jax
import jax.scipy.linalg
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import bodies as bd
from . import forces as fc
from . import joints as jt
from . import quaternion as qt
from .axle_frame import ElementView
from .state import State
from .system import System, SystemParams, _element_states, stateful_groups


def mass_matrix(system: System, params: SystemParams, q) -> Float[Array, "7n 7n"]:
    """Block-diagonal mass matrix (7 n, 7 n) in the (rdot, pdot) velocities."""
    _, p = bd.split_coordinates(q)
    blocks = jax.vmap(bd.body_mass_matrix)(params.bodies.mass, params.bodies.inertia, p)
    n = system.n_bodies
    placed = jnp.eye(n)[:, None, :, None] * blocks[:, :, None, :]  # (n, 7, n, 7)
    return placed.reshape(7 * n, 7 * n)


def quadratic_velocity(system: System, params: SystemParams, q, qdot) -> Array:
    """h (7 n,), the quadratic velocity vector 8 Gdot^T J' Gdot p of each body."""
    _, p = bd.split_coordinates(q)
    _, pdot = bd.split_coordinates(qdot)
    h = jax.vmap(bd.body_quadratic_velocity)(params.bodies.inertia, p, pdot)
    return h.reshape(-1)


def constraints(system: System, params: SystemParams, q, qdot):
    """(Phi (m,), Phi_q (m, 7 n), Phidot (m,), gamma (m,)), m = system.n_constraints.

    Rows: normalisation of each body, then the joints kind by kind (JOINT_KINDS order).
    """
    parts = [jt.normalization_terms(q, qdot)]
    for g in system.joint_groups:
        parts.append(jt.joint_terms(g.kind, g.body_i, g.body_j, params.joints[g.kind],
                                    q, qdot))
    return tuple(jnp.concatenate(x, axis=0) for x in zip(*parts))


def generalized_forces(system: System, params: SystemParams, t, q, qdot,
                       external=None, elements=None) -> Array:
    """Applied generalized forces g (7 n,): gravity, force elements and `external`.

    external: None or a callable (t, q, qdot) -> (forces (n, 3) [N], torques (n, 3)
    [N m]), global, applied at the centres of mass (an equinox Module carrying its own
    parameters keeps them differentiable; any :class:`~jaxrail.multibody.loads.AbstractLoads`
    is one). elements: the force elements' internal
    states ``{kind: (k, r)}`` (:class:`State`), where the system has such elements.
    """
    g = fc.gravity_forces(params.bodies.mass, params.gravity, system.n_bodies)
    view = ElementView(system.axle_bodies, q, qdot)
    on_view = jnp.zeros_like(g) if system.axle_bodies else g  # summed as the elements see
    for grp in system.force_groups:
        on_view = on_view + fc.element_forces(grp.kind, grp.body_i, grp.body_j,
                                              params.forces[grp.kind], view.q, view.qdot,
                                              _element_states(system, elements, grp.kind))
    g = g + view.pull(on_view) if system.axle_bodies else on_view
    if external is not None:
        forces, torques = external(t, q, qdot)
        n = system.n_bodies
        if jnp.shape(forces) != (n, 3) or jnp.shape(torques) != (n, 3):
            raise ValueError(f"external must return forces and torques of shape ({n}, 3)"
                             f", got {jnp.shape(forces)} and {jnp.shape(torques)}")
        g = g + fc.centre_loads(q, forces, torques)
    return g


def element_rates(system: System, params: SystemParams, q, qdot, elements) -> dict:
    """``{kind: (k, r)}``: the rates of the force elements' internal states."""
    groups = stateful_groups(system)
    view = ElementView(system.axle_bodies if groups else (), q, qdot)
    return {g.kind: fc.element_loads(g.kind, g.body_i, g.body_j, params.forces[g.kind],
                                     view.q, view.qdot, elements[g.kind])[1]
            for g in groups}


def initial_element_states(system: System, params: SystemParams, q) -> dict:
    """``{kind: (k, r)}``: the force elements' internal states at rest at q (7 n,), each
    element unloaded through them (``forces.ForceKind.initial``)."""
    q = ElementView(system.axle_bodies, jnp.asarray(q, dtype=jnp.float64)).q
    return {g.kind: fc.element_initial_states(g.kind, g.body_i, g.body_j,
                                              params.forces[g.kind], q)
            for g in stateful_groups(system)}


def initial_state(system: System, params: SystemParams, q, qdot, track=None) -> State:
    """The :class:`State` (q, qdot) with the flexible track's rails ``track`` (or None)
    and the force elements' internal states at rest at q."""
    q = jnp.asarray(q, dtype=jnp.float64)
    return State.of(q, qdot, track, initial_element_states(system, params, q))


def _check_state(system, q, qdot):
    shape = (7 * system.n_bodies,)
    for name, x in (("q", q), ("qdot", qdot)):
        if x.shape != shape:
            raise ValueError(f"{name} must have shape {shape} (7 per body), got {x.shape}")


def _right_hand_sides(system, params, t, q, qdot, external, elements=None):
    """(g + h (7 n,), rhs_bottom (m,), phi_q (m, 7 n)) of eq. (19)."""
    phi, phi_q, phidot, gamma = constraints(system, params, q, qdot)
    rhs_top = generalized_forces(system, params, t, q, qdot, external, elements)
    rhs_top = rhs_top + quadratic_velocity(system, params, q, qdot)
    alpha, beta = params.baumgarte_alpha, params.baumgarte_beta
    rhs_bottom = gamma - 2.0 * alpha * phidot - beta**2 * phi
    return rhs_top, rhs_bottom, phi_q


def _inverse3(a):
    """Inverse of a (..., 3, 3) matrix by its adjugate (small, exact derivatives)."""
    c0 = jnp.cross(a[..., 1, :], a[..., 2, :])
    c1 = jnp.cross(a[..., 2, :], a[..., 0, :])
    c2 = jnp.cross(a[..., 0, :], a[..., 1, :])
    det = qt.dot(a[..., 0, :], c0)
    return jnp.stack([c0, c1, c2], axis=-1) / det[..., None, None]


def _inverse_mass(params, p):
    """The pieces of W, the inverse of M on the complement of the normalisation rows:
    (1 / m (n,), G(p) (n, 3, 4), J'^-1 / (4 s^2) (n, 3, 3)) with s = p . p."""
    s = qt.dot(p, p)
    k = _inverse3(params.bodies.inertia) / (4.0 * s * s)[:, None, None]
    return 1.0 / params.bodies.mass, jax.vmap(qt.g_matrix)(p), k


def _apply_w(w, v):
    """W v per body: v (..., n, 7) -> (..., n, 7), W = blockdiag(I / m, G^T K G)."""
    inv_m, g, k = w
    a = qt.matvec(g, v[..., 3:])  # (..., n, 3)
    b = qt.matvec(k, a)
    return jnp.concatenate([v[..., :3] * inv_m[:, None],
                            jnp.sum(g * b[..., :, None], axis=-2)], axis=-1)


def _lean_solve(params, q, rhs_top, rhs_bottom, phi_q):
    """(qddot, lambda) of eq. (19) by the Schur complement on the joint rows.

    Per body, with s = p . p, L = G(p): G G^T = s I3 and G^T G = s I4 - p p^T, so
    pddot = G^T a + p b with a from the rotational equations multiplied by G (the
    normalisation multiplier drops out: G p = 0) and b from the normalisation row.
    Hence qddot = W (f - Phi_j^T lambda_j) + c, W = blockdiag(I / m, G^T J'^-1 G
    / (4 s^2)), c = (0, p gamma_n / (2 s)): exact for any |p|. The joint multipliers
    solve S lambda_j = Phi_j (W f + c) - gamma_j with S = Phi_j W Phi_j^T (SPD for
    independent joints); the normalisation ones follow from the rows along p.
    """
    n = q.shape[0] // 7
    p = q.reshape(n, 7)[:, 3:]
    s = qt.dot(p, p)
    w = _inverse_mass(params, p)
    f = rhs_top.reshape(n, 7)
    rhs_n, rhs_j = rhs_bottom[:n], rhs_bottom[n:]
    c = jnp.concatenate([jnp.zeros((n, 3), dtype=q.dtype),
                         p * (0.5 * rhs_n / s)[:, None]], axis=1)
    free = _apply_w(w, f) + c  # (n, 7): the accelerations without joint reactions
    phi_j = phi_q[n:]
    nj = phi_j.shape[0]
    if nj == 0:
        lam_j = jnp.zeros((0,), dtype=q.dtype)
        qddot = free.reshape(-1)
        reaction = jnp.zeros_like(f)
    else:
        x = _apply_w(w, phi_j.reshape(nj, n, 7)).reshape(nj, 7 * n)  # Phi_j W
        schur = x @ phi_j.T
        residual = phi_j @ free.reshape(-1) - rhs_j
        lam_j = jax.scipy.linalg.cho_solve(jax.scipy.linalg.cho_factor(schur),
                                           residual)
        qddot = free.reshape(-1) - lam_j @ x
        reaction = (lam_j @ phi_j).reshape(n, 7)
    lam_n = 0.5 * qt.dot(p, f[:, 3:] - reaction[:, 3:]) / s
    return qddot, jnp.concatenate([lam_n, lam_j])


def acceleration_response(system: System, params: SystemParams, q, qdot, bodies, blocks):
    """d qddot / d x for body-local loads: ``blocks`` (k, 7, m) is the derivative of
    the generalized load (7,) on each body of ``bodies`` (k static indices) with
    respect to m quantities of its own (e.g. its q and qdot, m = 14); returns the
    accelerations (7 n, k, m) they cause, the joint reactions included.

    With q, qdot fixed eq. (19) is affine in the loads g; its linear part is
    `_lean_solve`'s W - (Phi_j W)^T S^-1 (Phi_j W), applied here body by body."""
    n, k = system.n_bodies, len(bodies)
    if k == 0:  # no body with stiff loads (AbstractLoads.linearised's default)
        return jnp.zeros((7 * n, 0, blocks.shape[2]), dtype=q.dtype)
    index = np.asarray(bodies, dtype=int)
    _, phi_q, _, _ = constraints(system, params, q, qdot)
    w = _inverse_mass(params, q.reshape(n, 7)[:, 3:])
    columns = jnp.moveaxis(blocks, 2, 0)  # (m, k, 7)
    own = _apply_w(tuple(x[index] for x in w), columns)  # (m, k, 7)
    free = jnp.zeros((n, 7, k, blocks.shape[2]), dtype=q.dtype)
    free = free.at[index, :, np.arange(k), :].set(jnp.moveaxis(own, 0, 2))
    free = free.reshape(7 * n, k, -1)
    phi_j = phi_q[n:]
    nj = phi_j.shape[0]
    if nj == 0:
        return free
    x = _apply_w(w, phi_j.reshape(nj, n, 7))  # Phi_j W (nj, n, 7)
    factor = jax.scipy.linalg.cho_factor(x.reshape(nj, -1) @ phi_j.T)
    load_rows = jnp.einsum("rkc,kcm->rkm", x[:, index, :], blocks)
    lam = jax.scipy.linalg.cho_solve(factor, load_rows.reshape(nj, -1))
    return free - (x.reshape(nj, -1).T @ lam).reshape(free.shape)


def _augmented_solve(mass, phi_q, rhs_top, rhs_bottom):
    """(qddot, lambda) of eq. (19) by one dense LU solve of the augmented matrix (the
    reference for `_lean_solve`)."""
    m = phi_q.shape[0]
    lhs = jnp.block([[mass, phi_q.T], [phi_q, jnp.zeros((m, m), dtype=mass.dtype)]])
    sol = jnp.linalg.solve(lhs, jnp.concatenate([rhs_top, rhs_bottom]))
    return sol[: mass.shape[0]], sol[mass.shape[0]:]


def accelerations(system: System, params: SystemParams, t, q, qdot, external=None,
                  elements=None):
    """(qddot (7 n,), lambda (m,)) from eq. (19) with Baumgarte stabilisation;
    ``elements``: the force elements' internal states (:func:`generalized_forces`).

    Solved per body and on the joint rows only (`_lean_solve`), never with the dense
    augmented matrix; `accelerations_dense` is the same with the dense solve.
    """
    q = jnp.asarray(q, dtype=jnp.float64)
    qdot = jnp.asarray(qdot, dtype=jnp.float64)
    _check_state(system, q, qdot)
    rhs_top, rhs_bottom, phi_q = _right_hand_sides(system, params, t, q, qdot, external,
                                                   elements)
    return _lean_solve(params, q, rhs_top, rhs_bottom, phi_q)


def accelerations_dense(system: System, params: SystemParams, t, q, qdot,
                        external=None, elements=None):
    """`accelerations` by the dense LU solve of the augmented matrix [[M, Phi_q^T],
    [Phi_q, 0]] (the reference: slower, same result)."""
    q = jnp.asarray(q, dtype=jnp.float64)
    qdot = jnp.asarray(qdot, dtype=jnp.float64)
    _check_state(system, q, qdot)
    rhs_top, rhs_bottom, phi_q = _right_hand_sides(system, params, t, q, qdot, external,
                                                   elements)
    return _augmented_solve(mass_matrix(system, params, q), phi_q, rhs_top, rhs_bottom)
