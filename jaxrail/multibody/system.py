"""A constrained multibody system: assembly and the equations of motion, eq. (19).

Structure and parameters are separate (docs/design.md §2): `System` holds only static
topology (body count and names, and per joint or force kind the body indices of its
elements), so changing it recompiles; `SystemParams` holds every physical number as a
float64 array, so it can be batched (vmap) and differentiated. `build_system` makes
both from build-time descriptions (RigidBody, Revolute, Bushing, ...).

Equations of motion (Nikravesh; the paper's eq. 19 with Baumgarte stabilisation):

    [ M     Phi_q^T ] [ qddot  ]   [ g + h                              ]
    [ Phi_q 0       ] [ lambda ] = [ gamma - 2 alpha Phidot - beta^2 Phi ]

with M = blockdiag(m_i I3, 4 G_i^T J'_i G_i), g the applied generalized forces
(gravity, force elements, the `external` hook), h the quadratic velocity vector and
Phi the normalisation constraints followed by the joints. Sign of lambda: the joint
reactions on the bodies are -Phi_q^T lambda (for a spherical joint, -lambda is the
force [N] on body i and +lambda the force on body j, global frame).
"""

import dataclasses

import diffrax
import equinox as eqx
import jax
import jax.scipy.linalg
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from jaxrail._float64 import require_float64

from . import bodies as bd
from . import forces as fc
from . import joints as jt
from . import quaternion as qt
from ._values import checked_vector, float64_array
from .state import State


@dataclasses.dataclass(frozen=True)
class Group:
    """Static topology of the elements of one kind: body indices (-1 = ground)."""

    kind: str
    body_i: tuple[int, ...]
    body_j: tuple[int, ...]
    names: tuple[str, ...]


class System(eqx.Module):
    """Static structure of a multibody system (no array leaves; hashable).

    Fields: n_bodies; body_names; joint_groups and force_groups, one `Group` per kind
    present, in the order of joints.JOINT_KINDS and forces.FORCE_KINDS.
    """

    n_bodies: int = eqx.field(static=True)
    body_names: tuple[str, ...] = eqx.field(static=True)
    joint_groups: tuple[Group, ...] = eqx.field(static=True)
    force_groups: tuple[Group, ...] = eqx.field(static=True)

    @property
    def n_constraints(self) -> int:
        """Rows of Phi: one normalisation per body plus the joint equations."""
        rows = sum(jt.JOINT_KINDS[g.kind][0] * len(g.body_i) for g in self.joint_groups)
        return self.n_bodies + rows

    def find(self, name: str) -> tuple[str, str, int]:
        """("body", "", i) or ("joint" | "force", kind, index within its kind)."""
        if name in self.body_names:
            return "body", "", self.body_names.index(name)
        kinds = (("joint", self.joint_groups), ("force", self.force_groups))
        for what, groups in kinds:
            for g in groups:
                if name in g.names:
                    return what, g.kind, g.names.index(name)
        raise ValueError(f"name {name!r} is not a body, joint or force element")


class SystemParams(eqx.Module):
    """Traced parameters: bodies, joints[kind], forces[kind], gravity (3,) [m/s^2]
    (global), Baumgarte alpha [1/s] and beta [1/s] (scalars)."""

    bodies: bd.BodyParams
    joints: dict
    forces: dict
    gravity: Float[Array, " 3"]
    baumgarte_alpha: Float[Array, ""]
    baumgarte_beta: Float[Array, ""]


def _body_index(ref, names, what):
    if isinstance(ref, str):
        if ref == "ground":
            return -1
        if ref not in names:
            raise ValueError(f"{what}: unknown body {ref!r}")
        return names.index(ref)
    if isinstance(ref, (int, np.integer)) and -1 <= int(ref) < len(names):
        return int(ref)
    raise ValueError(f"{what}: body must be a name, 'ground' or an index in [-1, "
                     f"{len(names)}), got {ref!r}")


def _resolve(element, names, what):
    bi = _body_index(element.body_i, names, f"{what} body_i")
    bj = _body_index(element.body_j, names, f"{what} body_j")
    if bi == bj:
        raise ValueError(f"{what}: body_i and body_j must differ, both are {bi}")
    checked_vector(element.point_i, (3,), f"{what} point_i")
    checked_vector(element.point_j, (3,), f"{what} point_j")
    return bi, bj


def _joint_params(specs):
    frames = [s.frames() for s in specs]
    return jt.JointParams(
        point_i=float64_array([s.point_i for s in specs]),
        point_j=float64_array([s.point_j for s in specs]),
        frame_i=float64_array([f[0] for f in frames]),
        frame_j=float64_array([f[1] for f in frames]),
    )


def _groups(elements, kinds, names, what):
    groups, by_kind = [], {}
    for e in elements:
        if getattr(e, "kind", None) not in kinds:
            raise ValueError(f"{what} kind must be one of {sorted(kinds)}, got "
                             f"{getattr(e, 'kind', None)!r} ({e!r})")
    for kind in kinds:
        specs = [e for e in elements if e.kind == kind]
        if not specs:
            continue
        idx = [_resolve(s, names, f"{what} {s.name or kind!r}") for s in specs]
        groups.append(Group(kind, tuple(i for i, _ in idx), tuple(j for _, j in idx),
                            tuple(s.name for s in specs)))
        by_kind[kind] = specs
    return tuple(groups), by_kind


def build_system(bodies, joints=(), forces=(), gravity=(0.0, 0.0, 0.0),
                 baumgarte=(10.0, 10.0)) -> tuple[System, SystemParams]:
    """(System, SystemParams) from build-time descriptions.

    Arguments:
        bodies: sequence of RigidBody (n >= 1); body index = position in it.
        joints: Spherical / Revolute / Prismatic / Fixed; bodies by name, index, or
            "ground" / -1 for the fixed global frame.
        forces: descriptions of any kind of forces.FORCE_KINDS (SpringDamper, Bushing,
            BumpStop, TableSpring, AntiRollBar, FrictionDamper, TractionRod,
            MaxwellDamper, AirSpring).
        gravity: (3,) [m/s^2], global; e.g. (0, 0, -9.81) with z up.
        baumgarte: (alpha, beta) [1/s], feedback gains of eq. (19).
    """
    require_float64("a multibody system")
    bodies = tuple(bodies)
    if not bodies or not all(isinstance(b, bd.RigidBody) for b in bodies):
        raise ValueError("bodies must be a non-empty sequence of RigidBody")
    names = tuple(b.name for b in bodies)
    if len(set(names)) != len(names) or "ground" in names:
        raise ValueError(f"bodies must have unique names other than 'ground': {names}")
    inertia = [b.inertia_tensor() for b in bodies]
    alpha, beta = checked_vector(baumgarte, (2,), "baumgarte")
    if alpha < 0.0 or beta < 0.0:
        raise ValueError(f"baumgarte gains must be >= 0, got {baumgarte}")
    joint_groups, joint_specs = _groups(tuple(joints), jt.JOINT_KINDS, names, "joint")
    force_groups, force_specs = _groups(tuple(forces), fc.FORCE_KINDS, names, "force")
    system = System(len(bodies), names, joint_groups, force_groups)
    params = SystemParams(
        bodies=bd.BodyParams(float64_array([b.mass for b in bodies]), float64_array(inertia)),
        joints={k: _joint_params(s) for k, s in joint_specs.items()},
        forces={k: fc.FORCE_KINDS[k].params(s, f"force {k}") for k, s in force_specs.items()},
        gravity=float64_array(checked_vector(gravity, (3,), "gravity")),
        baumgarte_alpha=float64_array(alpha),
        baumgarte_beta=float64_array(beta),
    )
    return system, params


# ---- assembly -----------------------------------------------------------------


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


def stateful_groups(system: System) -> tuple[Group, ...]:
    """The force groups whose kind has internal states (``State.elements``' keys)."""
    return tuple(g for g in system.force_groups if fc.FORCE_KINDS[g.kind].states > 0)


def _element_states(system, elements, kind):
    """The internal states (k, r) of ``kind``'s elements, or None for a stateless kind
    (ValueError if a stateful kind's are missing)."""
    if fc.FORCE_KINDS[kind].states == 0:
        return None
    if elements is None or kind not in elements:
        raise ValueError(f"the {kind} elements have internal states: pass them "
                         f"(State.elements[{kind!r}], :func:`initial_element_states`)")
    return elements[kind]


def generalized_forces(system: System, params: SystemParams, t, q, qdot,
                       external=None, elements=None) -> Array:
    """Applied generalized forces g (7 n,): gravity, force elements and `external`.

    external: None or a callable (t, q, qdot) -> (forces (n, 3) [N], torques (n, 3)
    [N m]), global, applied at the centres of mass (an equinox Module carrying its own
    parameters keeps them differentiable). elements: the force elements' internal
    states ``{kind: (k, r)}`` (:class:`State`), where the system has such elements.
    """
    g = fc.gravity_forces(params.bodies.mass, params.gravity, system.n_bodies)
    for grp in system.force_groups:
        g = g + fc.element_forces(grp.kind, grp.body_i, grp.body_j,
                                  params.forces[grp.kind], q, qdot,
                                  _element_states(system, elements, grp.kind))
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
    return {g.kind: fc.element_loads(g.kind, g.body_i, g.body_j, params.forces[g.kind], q,
                                     qdot, elements[g.kind])[1]
            for g in stateful_groups(system)}


def initial_element_states(system: System, params: SystemParams, q) -> dict:
    """``{kind: (k, r)}``: the force elements' internal states at rest at q (7 n,), each
    element unloaded through them (``forces.ForceKind.initial``)."""
    q = jnp.asarray(q, dtype=jnp.float64)
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


class FixedLoads(eqx.Module):
    """An ``external`` hook that returns loads computed beforehand: forces and torques
    (n, 3) [N, N m], global."""

    forces: jax.Array
    torques: jax.Array

    def __call__(self, t, q, qdot):
        return self.forces, self.torques


def rhs(t, y: State, args) -> State:
    """diffrax vector field of a :class:`State`, args = (system, params[, external]).

    Where the state has a flexible track (``y.track``), ``external.coupled(t, q, qdot,
    track)`` returns the bodies' loads (forces, torques (n, 3)) and the track's
    derivatives (the structure of ``y.track``); otherwise ``external(t, q, qdot)``
    returns the loads. The force elements' internal states move at their kinds' rates.
    """
    system, params, *rest = args
    external = rest[0] if rest else None
    q, qdot = y.q, y.qdot
    track_dot = None
    if y.track is not None:
        forces, torques, track_dot = external.coupled(t, q, qdot, y.track)
        external = FixedLoads(forces, torques)
    qddot, _ = accelerations(system, params, t, q, qdot, external, y.elements)
    return State(qdot, qddot, track_dot, element_rates(system, params, q, qdot, y.elements))


# ---- diagnostics --------------------------------------------------------------------


@eqx.filter_jit
def constraint_violation(system: System, params: SystemParams, q, qdot):
    """(max |Phi|, max |Phidot|) over all constraint rows (m or -, m/s or 1/s)."""
    phi, _, phidot, _ = constraints(system, params, q, qdot)
    return jnp.max(jnp.abs(phi)), jnp.max(jnp.abs(phidot))


@eqx.filter_jit
def kinetic_energy(system: System, params: SystemParams, q, qdot) -> Array:
    """Total kinetic energy [J]."""
    _, p = bd.split_coordinates(q)
    rdot, pdot = bd.split_coordinates(qdot)
    b = params.bodies
    return jnp.sum(jax.vmap(bd.body_kinetic_energy)(b.mass, b.inertia, p, rdot, pdot))


@eqx.filter_jit
def potential_energy(system: System, params: SystemParams, q, elements=None) -> Array:
    """Gravity (-m g . r) plus the energy stored in the force elements [J];
    ``elements``: their internal states, where the system has such elements."""
    r, _ = bd.split_coordinates(q)
    v = -jnp.sum(params.bodies.mass * (r @ params.gravity))
    for g in system.force_groups:
        v = v + fc.element_potential(g.kind, g.body_i, g.body_j, params.forces[g.kind], q,
                                     _element_states(system, elements, g.kind))
    return v


@eqx.filter_jit
def dissipated_power(system: System, params: SystemParams, q, qdot, elements=None) -> Array:
    """The power [W] the force elements dissipate at this state (>= 0)."""
    return sum((fc.element_power(g.kind, g.body_i, g.body_j, params.forces[g.kind], q, qdot,
                                 _element_states(system, elements, g.kind))
                for g in system.force_groups), jnp.zeros((), dtype=jnp.float64))


@eqx.filter_jit
def angular_momentum(system: System, params: SystemParams, q, qdot) -> Array:
    """Total angular momentum (3,) [kg m^2/s] about the global origin, global frame."""
    r, p = bd.split_coordinates(q)
    rdot, pdot = bd.split_coordinates(qdot)
    b = params.bodies
    each = jax.vmap(bd.body_angular_momentum)(b.mass, b.inertia, r, p, rdot, pdot)
    return jnp.sum(each, axis=0)


def _minimum_norm_solution(phi_q, rhs):
    """x of least Euclidean norm with ``phi_q x = rhs``: ``phi_q^T (phi_q phi_q^T)^-1 rhs``
    (``phi_q`` of full row rank, as the equations of motion need anyway).

    The normal equations take one LU solve of an m x m matrix, cheaper than the SVD
    of ``pinv``, with the same result."""
    return phi_q.T @ jnp.linalg.solve(phi_q @ phi_q.T, rhs)


def project_state(system: System, params: SystemParams, q, qdot):
    """(q, qdot) moved onto the constraints by one Gauss-Newton step, q - Phi_q^+ Phi,
    then qdot projected onto Phi_q qdot = 0 (minimum-norm corrections; for the small
    drift an integration step leaves, the second step would change q by about
    |Phi|^2)."""
    phi, phi_q, _, _ = constraints(system, params, q, qdot)
    q = q - _minimum_norm_solution(phi_q, phi)
    _, phi_q, _, _ = constraints(system, params, q, qdot)
    return q, qdot - _minimum_norm_solution(phi_q, phi_q @ qdot)


@eqx.filter_jit
def consistent_initial_conditions(system: System, params: SystemParams, q0, qdot0,
                                  iterations: int = 12):
    """(q, qdot) with Phi(q) = 0 and Phi_q qdot = 0, nearest to (q0, qdot0).

    A fixed number of Gauss-Newton steps with the minimum-norm correction
    q <- q - Phi_q^+ Phi, then the Euclidean projection of qdot0 onto the null
    space of Phi_q (coordinates and velocities mixed without weights, so give a good
    guess for the coordinates you care about).
    """
    zeros = jnp.zeros_like(jnp.asarray(qdot0, dtype=jnp.float64))

    def step(_, q):
        phi, phi_q, _, _ = constraints(system, params, q, zeros)
        return q - _minimum_norm_solution(phi_q, phi)

    q = jax.lax.fori_loop(0, iterations, step, jnp.asarray(q0, dtype=jnp.float64))
    _, phi_q, _, _ = constraints(system, params, q, zeros)
    qdot0 = jnp.asarray(qdot0, dtype=jnp.float64)
    return q, qdot0 - _minimum_norm_solution(phi_q, phi_q @ qdot0)


def simulate_system(system: System, params: SystemParams, q0, qdot0, t1, dt0=1e-3,
                    saveat=None, rtol=1e-8, atol=1e-8, solver=None, t0=0.0,
                    external=None, max_steps=100_000, adjoint=None, throw=True,
                    stepsize_controller=None, event=None, progress_meter=None,
                    track0=None, elements0=None):
    """Integrate eq. (19) with diffrax from (q0, qdot0) at t0 [s] to t1 [s].

    Returns diffrax's Solution, with ys a :class:`State` (q (..., 7 n), qdot (..., 7
    n), ...) at `saveat` (default: t1 only). ``track0``: a flexible track's rails at t0
    (a pytree of arrays, integrated with the bodies through ``external.coupled``,
    :func:`rhs`); ``elements0``: the force elements' internal states at t0 (default:
    at rest at q0, :func:`initial_element_states`). solver defaults to Tsit5;
    stepsize_controller to a PIDController with rtol, atol (pass
    diffrax.ConstantStepSize() for fixed steps dt0); adjoint to
    RecursiveCheckpointAdjoint (reverse-mode AD works). event and progress_meter are
    passed to diffrax (a terminating diffrax.Event, a progress meter).
    """
    q0 = jnp.asarray(q0, dtype=jnp.float64)
    if elements0 is None:
        elements0 = initial_element_states(system, params, q0)
    y0 = State.of(q0, qdot0, track0, elements0)
    solver = diffrax.Tsit5() if solver is None else solver
    args = (system, params, external)
    # Tsit5 is first-same-as-last: its state is the last stage. Given at the start,
    # the first step does not evaluate its first stage again at each rejected attempt
    # (diffrax's own start does), so every attempt costs 6 right-hand sides.
    solver_state = ((jnp.asarray(False), rhs(t0, y0, args)) if type(solver) is diffrax.Tsit5
                    else None)
    return diffrax.diffeqsolve(
        diffrax.ODETerm(rhs),
        solver,
        t0,
        t1,
        dt0,
        y0,
        args=args,
        saveat=diffrax.SaveAt(t1=True) if saveat is None else saveat,
        stepsize_controller=(diffrax.PIDController(rtol=rtol, atol=atol)
                             if stepsize_controller is None else stepsize_controller),
        max_steps=max_steps,
        adjoint=diffrax.RecursiveCheckpointAdjoint() if adjoint is None else adjoint,
        throw=throw,
        event=event,
        progress_meter=diffrax.NoProgressMeter() if progress_meter is None else progress_meter,
        solver_state=solver_state,
    )
