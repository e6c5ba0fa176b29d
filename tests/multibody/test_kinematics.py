"""Euler parameters, joint constraints and generalized forces against independent
references: jax.jacfwd of Phi, finite differences, virtual work and power, Euler's
equations. Kernels run under jit and vmap; gradients are checked with finite
differences."""

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrail.multibody as mb
from jaxrail.multibody import forces as fc
from jaxrail.multibody import joints as jt
from jaxrail.multibody import quaternion as qt

RNG = np.random.default_rng(7)


def random_unit(n):
    v = RNG.normal(size=n)
    return v / np.linalg.norm(v)


def random_body_state():
    """q (7,) with unit p, and qdot (7,) with pdot tangent to the unit sphere."""
    p = random_unit(4)
    pdot = RNG.normal(size=4)
    pdot -= p * (p @ pdot)
    return (np.concatenate([RNG.normal(size=3), p]),
            np.concatenate([RNG.normal(size=3), pdot]))


def skew_np(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


# ---- Euler parameters --------------------------------------------------


@jax.jit
def _quaternion_identities(p, pdot):
    a = qt.rotation_matrix(p)
    adot = jax.jvp(qt.rotation_matrix, (p,), (pdot,))[1]
    return dict(
        orth=a @ a.T, a=a, eg=qt.e_matrix(p) @ qt.g_matrix(p).T, gp=qt.g_matrix(p) @ p,
        adot=adot, rate=qt.rotation_matrix_rate(p, pdot),
        w_body=2.0 * qt.g_matrix(p) @ pdot, w=2.0 * qt.e_matrix(p) @ pdot,
    )


def test_euler_parameter_identities():
    p = random_unit(4)
    pdot = RNG.normal(size=4)
    pdot -= p * (p @ pdot)
    d = jax.tree.map(np.asarray, _quaternion_identities(p, pdot))
    e0, e = p[0], p[1:]
    a_ref = (2 * e0**2 - 1) * np.eye(3) + 2 * (np.outer(e, e) + e0 * skew_np(e))
    np.testing.assert_allclose(d["a"], a_ref, atol=1e-15)
    np.testing.assert_allclose(d["orth"], np.eye(3), atol=1e-15)
    np.testing.assert_allclose(d["eg"], a_ref, atol=1e-15)
    np.testing.assert_allclose(d["gp"], 0.0, atol=1e-15)
    np.testing.assert_allclose(d["rate"], d["adot"], atol=1e-14)
    # Adot = A omega'~ = omega~ A: the angular velocities of Nikravesh's G and E.
    np.testing.assert_allclose(d["adot"], a_ref @ skew_np(d["w_body"]), atol=1e-14)
    np.testing.assert_allclose(d["adot"], skew_np(d["w"]) @ a_ref, atol=1e-14)


ROUND_TRIP = [((1, 0, 0), 3.1), ((0, 1, 0), -3.14159), ((0, 0, 1), 3.0),
              ((1, 2, 3), 0.7), ((-1, 0.5, 0.2), 2.5)]


@jax.jit
@jax.vmap
def _round_trip(axis, angle):
    p = qt.from_axis_angle(axis, angle)
    r = qt.from_axis_angle(jnp.array([0.3, -1.0, 0.2]), 0.4)
    return (p, qt.from_rotation_matrix(qt.rotation_matrix(p)), qt.rotation_matrix(p),
            qt.rotation_matrix(qt.multiply(p, r)),
            qt.rotation_matrix(p) @ qt.rotation_matrix(r))


def test_rotation_matrix_round_trip():
    axes = np.array([a for a, _ in ROUND_TRIP], dtype=float)
    angles = np.array([t for _, t in ROUND_TRIP])
    p, back, a, a_pr, a_p_a_r = (np.asarray(x) for x in _round_trip(axes, angles))
    np.testing.assert_allclose(np.abs(np.sum(back * p, axis=1)), 1.0, atol=1e-14)
    for k, (axis, angle) in enumerate(ROUND_TRIP):
        u = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
        # Rodrigues' formula as the independent reference.
        ref = (np.cos(angle) * np.eye(3) + np.sin(angle) * skew_np(u)
               + (1 - np.cos(angle)) * np.outer(u, u))
        np.testing.assert_allclose(a[k], ref, atol=1e-15)
    np.testing.assert_allclose(a_pr, a_p_a_r, atol=1e-15)


def test_from_rotation_matrix_gradient_is_finite_and_matches_fd():
    def angle_z(theta):  # recover the angle from the matrix of a z rotation
        p = qt.from_rotation_matrix(qt.rotation_matrix(qt.from_axis_angle(
            jnp.array([0.0, 0.0, 1.0]), theta)))
        return 2.0 * jnp.arctan2(p[3], p[0])

    g = jax.jit(jax.grad(angle_z))
    for theta in (0.0, 1.0, 3.0):
        assert np.isfinite(g(theta))
        np.testing.assert_allclose(g(theta), 1.0, rtol=1e-12)


# ---- joints ------------------------------------------------------------


def random_joint_params():
    return jt.JointParams(
        point_i=jnp.asarray(RNG.normal(size=3)),
        point_j=jnp.asarray(RNG.normal(size=3)),
        frame_i=jnp.asarray(jt.frame_from_axis(RNG.normal(size=3))),
        frame_j=jnp.asarray(jt.frame_from_axis(RNG.normal(size=3))),
    )


def test_spherical_gamma_matches_the_analytic_formula():
    # Nikravesh: with A quadratic in p, d2(A s')/ds2 along pdot is 2 (A(pdot) + I) s'.
    (qi, vi), (qj, vj) = random_body_state(), random_body_state()
    jp = random_joint_params()
    jet = jax.jit(lambda *a: jt.joint_jet("spherical", *a))(qi, qj, vi, vj, jp)

    def quad(pd, s):
        return 2.0 * (np.asarray(qt.rotation_matrix(pd)) + np.eye(3)) @ np.asarray(s)

    gamma = -quad(vi[3:], jp.point_i) + quad(vj[3:], jp.point_j)
    np.testing.assert_allclose(-jet.bias, gamma, atol=1e-13)


MOTIONS = ("spin", "tilt", "slide", "shift")
ALLOWED = {"spherical": ("spin", "tilt"), "revolute": ("spin",), "fixed": (),
           "prismatic": ("slide",)}


@jax.jit
def _joint_motions():
    """max |Phi| (kinds, motions) after moving body i from an assembled joint."""
    frame = jt.frame_from_axis((1.0, 2.0, 2.0))
    jp = jt.JointParams(jnp.zeros(3), jnp.zeros(3), jnp.asarray(frame),
                        jnp.asarray(frame))
    identity = jnp.array([0.0, 0, 0, 1, 0, 0, 0])
    axis, normal = jnp.asarray(frame[:, 2]), jnp.asarray(frame[:, 0])
    poses = {  # body i: spin about / tilt off the joint axis, slide along / across it
        "spin": (jnp.zeros(3), qt.from_axis_angle(axis, 0.3)),
        "tilt": (jnp.zeros(3), qt.from_axis_angle(normal, 0.3)),
        "slide": (0.3 * axis, identity[3:]),
        "shift": (0.3 * normal, identity[3:]),
    }
    return jnp.array([[jnp.max(jnp.abs(jt.joint_phi(kind, jnp.concatenate(poses[m]),
                                                     identity, jp)))
                       for m in MOTIONS] for kind in jt.JOINT_KINDS])


def test_joints_allow_exactly_their_motions():
    phi = np.asarray(_joint_motions())
    for k, kind in enumerate(jt.JOINT_KINDS):
        for m, motion in enumerate(MOTIONS):
            if motion in ALLOWED[kind]:
                assert phi[k, m] < 1e-15, (kind, motion)
            else:
                assert phi[k, m] > 1e-2, (kind, motion)


# ---- assembly on a system with every kind ------------------------------

SYSTEM, PARAMS = mb.build_system(
    [mb.RigidBody("a", 2.0, (1.0, 2.0, 3.0)),
     mb.RigidBody("b", 1.0, np.diag([0.5, 0.4, 0.3])),
     mb.RigidBody("c", 3.0, (0.2, 0.3, 0.25))],
    joints=[
        mb.Revolute("a", "ground", (0.1, 0.2, 0.3), (0.0, 0.0, 1.0), axis_i=(0, 1, 0),
                    axis_j=(0, 1, 0)),
        mb.Spherical("b", "a", (0.0, 0.0, 0.4), (0.0, 0.1, -0.5)),
        mb.Prismatic("c", "b", (0.1, 0.0, 0.0), (0.0, 0.2, 0.0), axis_i=(1, 0, 0),
                     axis_j=(1, 0, 0)),
        mb.Fixed("c", "ground", (0.0, 0.0, 0.0), (1.0, 1.0, 1.0)),
    ],
    forces=[
        mb.SpringDamper("a", "b", (0.1, 0.0, 0.0), (0.0, 0.3, 0.0), stiffness=300.0,
                        free_length=0.5, damping=7.0),
        mb.SpringDamper("c", "ground", (0.0, 0.1, 0.0), (0.5, 0.5, 0.5), stiffness=50.0,
                        free_length=1.0),
        mb.Bushing("b", "c", (0.0, 0.1, 0.2), (0.2, 0.0, 0.0),
                   stiffness=(1e3, 2e3, 3e3, 40.0, 50.0, 60.0),
                   damping=(10.0, 20.0, 30.0, 0.4, 0.5, 0.6),
                   frame_i=jt.frame_from_axis((0.0, 1.0, 1.0)),
                   preload=(1, 2, 3, 4, 5, 6)),
        mb.BumpStop("a", "c", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), axis_i=(1.0, 1.0, 0.0),
                    clearance=-5.0, stiffness=1e4, damping=30.0),
    ],
    gravity=(0.0, -1.0, -9.81),
)


def random_system_state():
    states = [random_body_state() for _ in range(SYSTEM.n_bodies)]
    return (jnp.asarray(np.concatenate([s[0] for s in states])),
            jnp.asarray(np.concatenate([s[1] for s in states])))


def tangent(q, g):
    """g with each body's p-component removed (it does no work on |p| = 1)."""
    g = np.asarray(g).reshape(-1, 7).copy()
    p = np.asarray(q).reshape(-1, 7)[:, 3:]
    g[:, 3:] -= p * np.sum(p * g[:, 3:], axis=1, keepdims=True)
    return g.reshape(-1)


FD_WEIGHTS = np.array([1.0, -8.0, 8.0, -1.0]) / 12.0  # at -2h, -h, h, 2h (times 1/h)


@jax.jit
def _assembly(params, q, qdot):
    phi, phi_q, phidot, gamma = mb.constraints(SYSTEM, params, q, qdot)
    jac = jax.jacfwd(lambda x: mb.constraints(SYSTEM, params, x, qdot)[0])(q)
    h = 1e-5
    # Phi_q(q + s qdot) qdot at four s, differentiated by FD: (Phi_q qdot)_q qdot.
    rates = jax.vmap(lambda s: mb.constraints(SYSTEM, params, q + s * qdot, qdot)[2])(
        h * jnp.array([-2.0, -1.0, 1.0, 2.0]))
    return phi, phi_q, phidot, gamma, jac, jnp.asarray(FD_WEIGHTS) @ rates / h


def test_global_phi_q_and_gamma():
    q, qdot = random_system_state()
    phi, phi_q, phidot, gamma, jac, fd = _assembly(PARAMS, q, qdot)
    assert phi.shape == (SYSTEM.n_constraints,) == (3 + 5 + 3 + 5 + 6,)
    np.testing.assert_allclose(phi_q, jac, atol=1e-13)
    np.testing.assert_allclose(phidot, jac @ qdot, atol=1e-12)
    np.testing.assert_allclose(-gamma, fd, atol=1e-7)


def _normalized(q):
    x = q.reshape(-1, 7)
    p = x[:, 3:] / jnp.linalg.norm(x[:, 3:], axis=1, keepdims=True)
    return jnp.concatenate([x[:, :3], p], axis=1).reshape(-1)


@jax.jit
def _forces(params, q, qdot):
    g = mb.generalized_forces(SYSTEM, params, 0.0, q, qdot)
    m = mb.mass_matrix(SYSTEM, params, q)
    t_grad = jax.grad(lambda v: mb.kinetic_energy(SYSTEM, params, q, v))(qdot)
    omega_body = jnp.stack([mb.angular_velocity(q, qdot, i)[1]
                            for i in range(SYSTEM.n_bodies)])

    # Central FD of V along each coordinate, with p normalised (V on the unit sphere).
    def fd(e, h=1e-6):
        return (mb.potential_energy(SYSTEM, params, _normalized(q + h * e))
                - mb.potential_energy(SYSTEM, params, _normalized(q - h * e))) / (2 * h)

    return g, m, t_grad, omega_body, jax.vmap(fd)(jnp.eye(q.shape[0]))


def test_conservative_forces_are_minus_the_gradient_of_the_potential():
    q, _ = random_system_state()
    zero_damping = eqx.tree_at(
        lambda p: (p.forces["spring_damper"].damping, p.forces["bushing"].damping,
                   p.forces["bump_stop"].damping),
        PARAMS, (jnp.zeros(2), jnp.zeros((1, 6)), jnp.zeros(1)))
    g, _, _, _, fd = _forces(zero_damping, q, jnp.zeros_like(q))
    fd = np.asarray(fd)
    scale = np.abs(fd).max()
    assert scale > 10.0  # the elements are loaded
    # Virtual work: g = -dV/dq on the unit sphere (central FD of the potential).
    np.testing.assert_allclose(tangent(q, g), -fd, rtol=1e-6, atol=1e-7 * scale)


def test_mass_matrix_is_the_hessian_of_kinetic_energy():
    q, qdot = random_system_state()
    _, m, t_grad, omega_body, _ = _forces(PARAMS, q, qdot)
    np.testing.assert_allclose(m @ qdot, t_grad, rtol=1e-12, atol=1e-12)
    # Independent kinetic energy from omega' = 2 G pdot: 1/2 m v^2 + 1/2 w J w.
    v = np.asarray(qdot).reshape(-1, 7)[:, :3]
    w, mass, inertia = (np.asarray(x) for x in (omega_body, PARAMS.bodies.mass,
                                                 PARAMS.bodies.inertia))
    t_ref = 0.5 * np.sum(mass * np.sum(v * v, axis=1))
    t_ref += 0.5 * np.einsum("ni,nij,nj->", w, inertia, w)
    np.testing.assert_allclose(0.5 * qdot @ m @ qdot, t_ref, rtol=1e-12)


def test_damping_dissipates():
    q, qdot = random_system_state()
    no_springs = eqx.tree_at(
        lambda p: (p.forces["spring_damper"].stiffness, p.forces["bushing"].stiffness,
                   p.forces["bushing"].preload, p.forces["bump_stop"].stiffness,
                   p.gravity),
        PARAMS, (jnp.zeros(2), jnp.zeros((1, 6)), jnp.zeros((1, 6)), jnp.zeros(1),
                 jnp.zeros(3)))
    g, *_ = _forces(no_springs, q, qdot)
    assert float(g @ qdot) < -1.0  # power of pure damping is negative


@jax.jit
def _point_loads(p, point, force, torque, pdot):
    w = 2.0 * qt.e_matrix(p) @ pdot  # global angular velocity
    v_point = jax.jvp(lambda x: qt.rotation_matrix(x) @ point, (p,), (pdot,))[1]
    return fc.point_force(p, point, force), fc.body_torque(p, torque), w, v_point


def test_point_force_and_torque_by_virtual_power():
    q, qdot = random_body_state()
    p, pdot = q[3:], qdot[3:]
    point, force, torque = RNG.normal(size=3), RNG.normal(size=3), RNG.normal(size=3)
    g_f, g_t, w, v_point = _point_loads(p, point, force, torque, pdot)
    # Power of a force at a moving point: f . (rdot + d/dt(A s')) = g . qdot.
    np.testing.assert_allclose(g_f @ qdot, force @ (qdot[:3] + v_point), rtol=1e-12)
    np.testing.assert_allclose(g_t @ qdot, torque @ w, rtol=1e-12)  # n . omega


def test_accelerations_of_a_free_body_follow_euler_equations():
    system, params = mb.build_system([mb.RigidBody("b", 2.0, (1.0, 2.0, 3.0))],
                                     gravity=(0.0, 0.0, -9.81))
    torque = jnp.array([0.3, -0.2, 0.5])

    def external(t, q, qdot):
        return jnp.zeros((1, 3)), torque[None]

    q, qdot = random_body_state()
    qddot, lam = jax.jit(lambda q, v: mb.accelerations(system, params, 0.0, q, v,
                                                       external))(q, qdot)
    p, pdot, pddot = q[3:], qdot[3:], np.asarray(qddot[3:])
    g_mat = np.asarray(qt.g_matrix(p))
    w = 2.0 * g_mat @ pdot
    a = np.asarray(qt.rotation_matrix(p))
    j = np.diag([1.0, 2.0, 3.0])
    w_dot = np.linalg.solve(j, a.T @ np.asarray(torque) - np.cross(w, j @ w))
    np.testing.assert_allclose(2.0 * g_mat @ pddot, w_dot, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(qddot[:3], [0.0, 0.0, -9.81], atol=1e-14)
    # The normalisation multiplier keeps p on the unit sphere: pddot . p = -|pdot|^2.
    np.testing.assert_allclose(pddot @ p, -pdot @ pdot, rtol=1e-12)
    assert lam.shape == (1,)


def test_bump_stop_is_one_sided():
    system, params = mb.build_system(
        [mb.RigidBody("b", 1.0, (1.0, 1.0, 1.0))],
        forces=[mb.BumpStop("ground", "b", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                            axis_i=(0.0, 0.0, 2.0), clearance=0.1, stiffness=1e3,
                            damping=50.0)])
    force = jax.jit(jax.vmap(lambda z, vz: mb.generalized_forces(
        system, params, 0.0, jnp.array([0.0, 0, z, 1, 0, 0, 0]),
        jnp.array([0.0, 0, vz, 0, 0, 0, 0]))[2]))
    fz = np.asarray(force(jnp.array([0.05, 0.15, 0.15, 0.15, -0.3]),
                          jnp.array([0.0, 0.0, 1.0, -10.0, -1.0])))
    np.testing.assert_allclose(fz, [0.0, -50.0, -100.0, 0.0, 0.0], atol=1e-12)


# ---- structure errors --------------------------------------------------------------


BODY = mb.RigidBody("a", 1.0, (1.0, 1.0, 1.0))


@pytest.mark.parametrize("kwargs, message", [
    (dict(bodies=[]), "bodies"),
    (dict(bodies=[BODY, BODY]), "unique"),
    (dict(bodies=[mb.RigidBody("a", -1.0, (1, 1, 1))]), "mass"),
    (dict(bodies=[mb.RigidBody("a", 1.0, (1, 1))]), "inertia"),
    (dict(bodies=[mb.RigidBody("a", 1.0, (1, -1, 1))]), "positive definite"),
    (dict(bodies=[BODY], joints=[mb.Spherical("a", "x", (0, 0, 0), (0, 0, 0))]),
     "unknown body"),
    (dict(bodies=[BODY], joints=[mb.Spherical("a", "a", (0, 0, 0), (0, 0, 0))]),
     "must differ"),
    (dict(bodies=[BODY], joints=[mb.Spherical("a", 3, (0, 0, 0), (0, 0, 0))]), "index"),
    (dict(bodies=[BODY], joints=[mb.Spherical("a", -1, (0, 0), (0, 0, 0))]), "point_i"),
    (dict(bodies=[BODY], joints=[mb.Revolute("a", -1, (0, 0, 0), (0, 0, 0),
                                             axis_i=(0, 0, 0))]), "axis_i"),
    (dict(bodies=[BODY], joints=["hinge"]), "joint"),
    (dict(bodies=[BODY], forces=[mb.BumpStop("a", -1, (0, 0, 0), (0, 0, 0), axis_i=(0, 0, 0),
                                             clearance=0.0, stiffness=1.0, name="stop")]),
     "bump_stop 'stop' axis_i must be a finite non-zero"),
    (dict(bodies=[BODY], forces=[mb.Bushing("a", -1, (0, 0, 0), (0, 0, 0),
                                            stiffness=(1, 2, 3))]), "stiffness"),
    (dict(bodies=[BODY], gravity=(0, -9.81)), "gravity"),
    (dict(bodies=[BODY], baumgarte=(-1.0, 1.0)), "baumgarte"),
])
def test_bad_structure_raises_value_error(kwargs, message):
    with pytest.raises(ValueError, match=message):
        mb.build_system(**kwargs)


def test_an_unknown_force_kind_is_named_not_built_as_another():
    """A force description whose kind is not in FORCE_KINDS (a torsion bar with the
    fields of a bump stop) is refused with its kind named; each known kind builds its
    own parameters."""
    @dataclasses.dataclass(frozen=True)
    class TorsionBar(mb.BumpStop):
        kind: ClassVar[str] = "torsion_bar"

    bar = TorsionBar("a", -1, (0, 0, 0), (0, 0, 0), axis_i=(0, 0, 1), clearance=0.0,
                     stiffness=1.0)
    with pytest.raises(ValueError, match="force kind must be one of .*got .torsion_bar."):
        mb.build_system([BODY], forces=[bar])
    elements = [mb.SpringDamper("a", -1, (0, 0, 0), (0, 0, 1), 1.0, 1.0),
                mb.Bushing("a", -1, (0, 0, 0), (0, 0, 0), stiffness=(1.0,) * 6),
                mb.BumpStop("a", -1, (0, 0, 0), (0, 0, 0), axis_i=(0, 0, 1), clearance=0.0,
                            stiffness=1.0)]
    _, params = mb.build_system([BODY], forces=elements)
    built = {kind: type(p).__name__ for kind, p in params.forces.items()}
    assert built == {"spring_damper": "SpringDamperParams", "bushing": "BushingParams",
                     "bump_stop": "BumpStopParams"}


def test_find_names():
    system, _ = mb.build_system(
        [BODY], joints=[mb.Spherical("a", "ground", (0, 0, 0), (0, 0, 0), name="ball")],
        forces=[mb.SpringDamper("a", "ground", (0, 0, 0), (0, 0, 1), 1.0, 1.0,
                                name="coil")])
    assert system.find("a") == ("body", "", 0)
    assert system.find("ball") == ("joint", "spherical", 0)
    assert system.find("coil") == ("force", "spring_damper", 0)
    with pytest.raises(ValueError, match="nope"):
        system.find("nope")


def test_bad_state_and_external_shapes_raise_value_error():
    system, params = mb.build_system([BODY])
    q = jnp.array([0.0, 0, 0, 1, 0, 0, 0])
    with pytest.raises(ValueError, match="qdot"):  # at trace time, under jit too
        jax.eval_shape(lambda: mb.accelerations(system, params, 0.0, q, jnp.zeros(6)))
    with pytest.raises(ValueError, match="external"):
        jax.eval_shape(lambda: mb.accelerations(
            system, params, 0.0, q, jnp.zeros(7),
            lambda t, q, v: (jnp.zeros((2, 3)), jnp.zeros((2, 3)))))
