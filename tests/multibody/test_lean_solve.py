"""The lean solve of eq. (19) (`accelerations`: per body, then the Schur complement on
the joint rows) against the dense augmented solve (`accelerations_dense`) and against
the equations themselves, on small systems with every joint kind and on the paper's
11-body trailer; its gradients against central finite differences, under jit and vmap.
"""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrail
import jaxrail.multibody as mb
from jaxrail.multibody.equations import _right_hand_sides

SOLVE_RTOL = 1e-9  # lean against dense, relative to the largest component
RESIDUAL_RTOL = 1e-12  # the rows of eq. (19), relative to their largest term
FD_RTOL = 1e-6

# Every joint kind, joints to the ground and between bodies, a chain (the Schur
# complement is not block diagonal), a free body with force elements, full inertia.
CHAIN, CHAIN_PARAMS = mb.build_system(
    [
        mb.RigidBody("upper", 1.0, (0.09, 0.1, 0.01)),
        mb.RigidBody("lower", 0.7, ((0.05, 0.01, 0.0), (0.01, 0.04, 0.002),
                                    (0.0, 0.002, 0.008))),
        mb.RigidBody("slider", 0.4, (0.01, 0.02, 0.03)),
        mb.RigidBody("welded", 0.3, (0.004, 0.005, 0.006)),
        mb.RigidBody("free", 2.0, (1.0, 2.0, 3.0)),
    ],
    joints=[
        mb.Revolute("upper", "ground", (0.0, 0.0, 0.5), (0.0, 0.0, 0.0),
                    axis_i=(0.0, 1.0, 0.0), axis_j=(0.0, 1.0, 0.0)),
        mb.Spherical("lower", "upper", (0.0, 0.0, 0.4), (0.0, 0.0, -0.5)),
        mb.Prismatic("lower", "slider", (0.1, 0.0, 0.0), (0.0, 0.0, 0.0),
                     axis_i=(1.0, 0.0, 0.0), axis_j=(1.0, 0.0, 0.0)),
        mb.Fixed("slider", "welded", (0.0, 0.1, 0.0), (0.0, -0.1, 0.0)),
    ],
    forces=[
        mb.SpringDamper("free", "ground", (0.1, 0.0, 0.0), (0.0, 0.0, 1.0),
                        stiffness=50.0, free_length=0.8, damping=2.0),
        mb.Bushing("free", "upper", (0.0, 0.0, 0.0), (0.0, 0.0, -0.5),
                   stiffness=(10.0, 20.0, 30.0, 4.0, 5.0, 6.0),
                   damping=(1.0, 1.0, 1.0, 0.1, 0.1, 0.1)),
        mb.BumpStop("slider", "lower", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                    axis_i=(1.0, 0.0, 0.0), clearance=-1.0, stiffness=100.0),
    ],
    gravity=(0.0, 0.0, -9.81),
)


def random_state(system, seed, p_scale=1.0, spread=0.3):
    """Random positions, random Euler parameters of norm p_scale, random velocities
    (constraints not satisfied: the two linear solves do not need it)."""
    rng = np.random.default_rng(seed)
    n = system.n_bodies
    p = rng.normal(size=(n, 4))
    p *= p_scale / np.linalg.norm(p, axis=1, keepdims=True)
    q = mb.join_coordinates(spread * rng.normal(size=(n, 3)), p)
    return q, jnp.asarray(rng.normal(size=7 * n))


@pytest.fixture(scope="module")
def trailer():
    jaxrail.enable_float64()
    from jaxrail.scenarios import load_scenario

    # eq. (19) with the axle joints: the file as written, not its joint-free form
    scenario = dataclasses.replace(load_scenario("paper-curve"), formulation="joints")
    vehicle, params, _ = scenario.build()
    return vehicle, params


def trailer_states(vehicle, params):
    """The nominal layout at rest (every bushing at zero deflection carrying its
    preload: the static equilibrium of the suspension) and a perturbed moving state
    with |p| != 1."""
    n = vehicle.system.n_bodies
    layout = np.asarray(params.layout)
    rest = mb.join_coordinates(layout, np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)))
    rng = np.random.default_rng(7)
    moved = rest + jnp.asarray(1e-2 * rng.normal(size=7 * n))
    return [(rest, jnp.zeros(7 * n)), (moved, jnp.asarray(rng.normal(size=7 * n)))]


@eqx.filter_jit
def both_solves(system, params, q, qdot):
    """Lean and dense (qddot, lambda); one compilation per system."""
    return (mb.accelerations(system, params, 0.0, q, qdot),
            mb.accelerations_dense(system, params, 0.0, q, qdot))


def assert_close(a, b, rtol):
    a, b = np.asarray(a), np.asarray(b)
    assert np.max(np.abs(a - b)) <= rtol * np.max(np.abs(b)), (
        f"max error {np.max(np.abs(a - b)):.3e} vs scale {np.max(np.abs(b)):.3e}")


def assert_solves_eq19(system, params, q, qdot, qddot, lam):
    """M qddot + Phi_q^T lambda = g + h and Phi_q qddot = rhs_bottom."""
    rhs_top, rhs_bottom, phi_q = _right_hand_sides(system, params, 0.0, q, qdot, None)
    mass = mb.mass_matrix(system, params, q)
    top_terms = [mass @ qddot, phi_q.T @ lam, rhs_top]
    scale = max(float(jnp.max(jnp.abs(t))) for t in top_terms)
    assert float(jnp.max(jnp.abs(top_terms[0] + top_terms[1] - top_terms[2]))) <= (
        RESIDUAL_RTOL * scale)
    scale = max(float(jnp.max(jnp.abs(phi_q * qddot))), float(jnp.max(jnp.abs(rhs_bottom))))
    assert float(jnp.max(jnp.abs(phi_q @ qddot - rhs_bottom))) <= RESIDUAL_RTOL * scale


@pytest.mark.parametrize("seed, p_scale", [(0, 1.0), (1, 1.0), (2, 0.9), (3, 1.3)])
def test_lean_solve_matches_dense_on_every_joint_kind(seed, p_scale):
    q, qdot = random_state(CHAIN, seed, p_scale)
    (qddot, lam), (qddot_ref, lam_ref) = both_solves(CHAIN, CHAIN_PARAMS, q, qdot)
    assert lam.shape == (CHAIN.n_constraints,)
    assert_close(qddot, qddot_ref, SOLVE_RTOL)
    assert_close(lam, lam_ref, SOLVE_RTOL)
    assert_solves_eq19(CHAIN, CHAIN_PARAMS, q, qdot, qddot, lam)


def test_lean_solve_without_joints():
    system, params = mb.build_system([mb.RigidBody("a", 1.5, (0.1, 0.2, 0.3)),
                                      mb.RigidBody("b", 0.5, (0.3, 0.2, 0.1))],
                                     gravity=(0.0, 0.0, -9.81))
    q, qdot = random_state(system, 4, 1.1)
    (qddot, lam), (qddot_ref, lam_ref) = both_solves(system, params, q, qdot)
    assert_close(qddot, qddot_ref, SOLVE_RTOL)
    assert_close(lam, lam_ref, SOLVE_RTOL)


def test_lean_solve_matches_dense_on_the_trailer(trailer):
    vehicle, vehicle_params = trailer
    system, params = vehicle.system, vehicle_params.system
    assert (7 * system.n_bodies, system.n_constraints) == (77, 31)
    for q, qdot in trailer_states(vehicle, vehicle_params):
        (qddot, lam), (qddot_ref, lam_ref) = both_solves(system, params, q, qdot)
        assert_close(qddot, qddot_ref, SOLVE_RTOL)
        assert_close(lam, lam_ref, SOLVE_RTOL)
        assert_solves_eq19(system, params, q, qdot, qddot, lam)


def _scalar(params, q, qdot):
    qddot, lam = mb.accelerations(CHAIN, params, 0.0, q, qdot)
    weights = jnp.linspace(0.5, 1.5, qddot.shape[0])
    return jnp.sum(weights * qddot) + 1e-3 * jnp.sum(lam)


def _with_mass(mass):
    return eqx.tree_at(lambda p: p.bodies.mass, CHAIN_PARAMS,
                       CHAIN_PARAMS.bodies.mass.at[1].set(mass))


def test_gradients_match_finite_differences():
    q, qdot = random_state(CHAIN, 5)
    direction = jnp.asarray(np.random.default_rng(6).normal(size=q.shape))
    grad_q, grad_m = jax.jit(jax.grad(
        lambda q, m: _scalar(_with_mass(m), q, qdot), argnums=(0, 1)))(q, 0.7)
    h = 1e-6
    scalar = jax.jit(lambda q, m: _scalar(_with_mass(m), q, qdot))

    def f(q, m):
        return float(scalar(q, m))

    fd_q = (f(q + h * direction, 0.7) - f(q - h * direction, 0.7)) / (2 * h)
    fd_m = (f(q, 0.7 + h) - f(q, 0.7 - h)) / (2 * h)
    assert float(grad_q @ direction) == pytest.approx(fd_q, rel=FD_RTOL)
    assert float(grad_m) == pytest.approx(fd_m, rel=FD_RTOL)
    # forward mode agrees with reverse mode
    jac_q = jax.jit(jax.jacfwd(lambda q: _scalar(CHAIN_PARAMS, q, qdot)))(q)
    np.testing.assert_allclose(np.asarray(jac_q), np.asarray(grad_q), rtol=1e-10,
                               atol=1e-10 * float(jnp.max(jnp.abs(grad_q))))


def test_vmap_matches_single_calls():
    states = [random_state(CHAIN, s) for s in (8, 9, 10)]
    qs = jnp.stack([s[0] for s in states])
    qdots = jnp.stack([s[1] for s in states])
    masses = jnp.array([0.7, 0.8, 0.9])

    def one(q, qdot, m):
        return mb.accelerations(CHAIN, _with_mass(m), 0.0, q, qdot)[0]

    batched = jax.jit(jax.vmap(one))(qs, qdots, masses)
    for k in range(3):
        ref = mb.accelerations_dense(CHAIN, _with_mass(masses[k]), 0.0, qs[k], qdots[k])[0]
        assert_close(batched[k], ref, SOLVE_RTOL)
    grads = jax.jit(jax.vmap(jax.grad(lambda q, v, m: jnp.sum(one(q, v, m)), argnums=2)))(
        qs, qdots, masses)
    assert np.all(np.isfinite(np.asarray(grads)))
