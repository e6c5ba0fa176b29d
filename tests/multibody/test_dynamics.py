"""Multibody dynamics against analytic results, on one "bench" system compiled once:

- bodies 0, 1: a 3-D double pendulum (revolute joint to the ground, spherical joint
  between the links): constraint violation with Baumgarte over 10 s, energy;
- body 2: a free rigid body with a spring and a six-component bushing to the ground at
  its centre: free body (energy, angular momentum), free fall, spring-mass frequency,
  torsional bushing frequency.

The subsystems do not interact, so switching gravity and stiffnesses (traced
parameters) gives every case from the same compiled simulation.
"""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrail.multibody as mb
from jaxrail.multibody import quaternion as qt

G = 9.81
N_SAVE = 201
SWING_TOL = 1e-10
MASS, INERTIA = 2.0, (1.0, 2.0, 3.0)  # the free body
FREE = slice(14, 21)  # its coordinates in q

BENCH, BENCH_PARAMS = mb.build_system(
    [
        mb.RigidBody("upper", 1.0, (0.09, 0.1, 0.01)),
        mb.RigidBody("lower", 0.7, (0.05, 0.04, 0.008)),
        mb.RigidBody("free", MASS, INERTIA),
    ],
    joints=[
        mb.Revolute("upper", "ground", (0.0, 0.0, 0.5), (0.0, 0.0, 0.0),
                    axis_i=(0.0, 1.0, 0.0), axis_j=(0.0, 1.0, 0.0)),
        mb.Spherical("lower", "upper", (0.0, 0.0, 0.4), (0.0, 0.0, -0.5)),
    ],
    forces=[
        mb.SpringDamper("free", "ground", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                        stiffness=0.0, free_length=1.0),
        mb.Bushing("free", "ground", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                   stiffness=(0.0,) * 6),
    ],
    gravity=(0.0, 0.0, -G),
    baumgarte=(10.0, 10.0),
)


@jax.jit
def _simulate_bench(params, q0, qdot0, ts, tol):
    sol = mb.simulate_system(mb.SystemLoads(BENCH, params), q0, qdot0, ts[-1], dt0=1e-3,
                             saveat=diffrax.SaveAt(ts=ts), rtol=tol, atol=tol)
    qs, qds = sol.ys.q, sol.ys.qdot

    def diagnostics(q, v):
        phi, phidot = mb.constraint_violation(BENCH, params, q, v)
        kinetic = mb.kinetic_energy(BENCH, params, q, v)
        r, a = mb.body_pose(q, 0)
        return dict(phi=phi, phidot=phidot, kinetic=kinetic,
                    energy=kinetic + mb.potential_energy(BENCH, params, q),
                    momentum=mb.angular_momentum(BENCH, params, q, v),
                    pivot=r + a @ jnp.array([0.0, 0.0, 0.5]),
                    w_free=mb.angular_velocity(q, v, 2)[1])

    return qs, qds, jax.vmap(diagnostics)(qs, qds)


def simulate_bench(params, q0, qdot0, ts, tol):
    """(q, qdot, diagnostics) at ts, as NumPy arrays; tol = rtol = atol is traced, so
    every run shares one compilation. Diagnostics per sample: max |Phi|, max |Phidot|,
    T, T + V, angular momentum, pivot of the upper link, free body's omega'."""
    return jax.tree.map(np.asarray, _simulate_bench(params, q0, qdot0, jnp.asarray(ts),
                                                    jnp.asarray(tol)))


def bench_params(gravity=G, spring=0.0, bushing=(0.0,) * 6):
    return eqx.tree_at(
        lambda p: (p.forces["spring_damper"].stiffness, p.forces["bushing"].stiffness,
                   p.gravity),
        BENCH_PARAMS,
        (jnp.asarray([spring], dtype=jnp.float64),
         jnp.asarray([bushing], dtype=jnp.float64),
         jnp.asarray([0.0, 0.0, -gravity], dtype=jnp.float64)),
    )


def bench_state(r_free, p_free, v_free, w_free, pendulum_moving):
    """A consistent initial state; the double pendulum hangs at rest unless moving."""
    if pendulum_moving:
        p1 = qt.from_axis_angle([0, 1.0, 0], 0.9)
        p2 = qt.from_axis_angle([1.0, 0.3, 0], 1.2)
        r12, w12 = [[0.4, 0.0, -0.3], [0.8, 0.3, -0.6]], [[0, 1.0, 0], [0.5, -2.0, 1.0]]
    else:
        p1 = p2 = jnp.array([1.0, 0.0, 0.0, 0.0])
        r12, w12 = [[0.0, 0.0, -0.5], [0.0, 0.0, -1.4]], [[0.0] * 3, [0.0] * 3]
    q = mb.join_coordinates(jnp.asarray(r12 + [list(r_free)]),
                            jnp.stack([p1, p2, jnp.asarray(p_free)]))
    qd = mb.velocities_from_twists(q, jnp.asarray([[0.0] * 3] * 2 + [list(v_free)]),
                                   jnp.asarray(w12 + [list(w_free)]))
    return mb.consistent_initial_conditions(BENCH, BENCH_PARAMS, q, qd)


@pytest.fixture(scope="module")
def swinging():
    """10 s with gravity: the double pendulum swings, the free body falls and spins.

    A moderate tolerance (1e-10), so that the constraint drift Baumgarte has to
    correct is visible (see test_baumgarte_stabilisation_reduces_the_drift)."""
    q0, qd0 = bench_state((0.0, 2.0, 0.0), qt.from_axis_angle([1, 1, 0.0], 0.3),
                          (1.0, 0.5, 2.0), (0.2, 0.0, 0.1), pendulum_moving=True)
    ts = jnp.linspace(0.0, 10.0, N_SAVE)
    qs, qds, d = simulate_bench(BENCH_PARAMS, q0, qd0, ts, SWING_TOL)
    return q0, qd0, np.asarray(ts), qs, qds, d


def test_consistent_initial_conditions(swinging):
    q0, qd0, *_, d = swinging
    assert d["phi"][0] < 1e-13 and d["phidot"][0] < 1e-13
    # The guess was far from consistent: the projection really moved it.
    guess_r = np.array([0.4, 0.0, -0.3])
    assert np.linalg.norm(np.asarray(q0[:3]) - guess_r) > 1e-2


def test_minimum_norm_correction_equals_the_pseudo_inverse():
    """The correction of consistent_initial_conditions against NumPy's SVD pinv, for a
    wide random matrix of full row rank, also under vmap."""
    from jaxrail.multibody.projection import _minimum_norm_solution

    rng = np.random.default_rng(3)
    phi_q, rhs = rng.normal(size=(4, 5, 9)), rng.normal(size=(4, 5))
    expected = np.einsum("bij,bj->bi", np.linalg.pinv(phi_q), rhs)
    assert np.allclose(_minimum_norm_solution(phi_q[0], rhs[0]), expected[0], atol=1e-12)
    assert np.allclose(jax.vmap(_minimum_norm_solution)(phi_q, rhs), expected, atol=1e-12)
    # rows on disjoint columns (a system without joints): the diagonal solve
    disjoint = phi_q * (np.arange(9)[None, None, :] // 2 == np.arange(5)[None, :, None])
    expected = np.einsum("bij,bj->bi", np.linalg.pinv(disjoint), rhs)
    solved = jax.vmap(lambda p, r: _minimum_norm_solution(p, r, True))(disjoint, rhs)
    assert np.allclose(solved, expected, atol=1e-12)


def test_double_pendulum_constraint_violation_over_10_s(swinging):
    *_, qs, _, d = swinging
    # Baumgarte alpha = beta = 10 1/s (build_system's default), rtol = atol = 1e-10.
    assert np.max(d["phi"]) < 1e-8 and np.max(d["phidot"]) < 1e-8
    assert np.max(np.abs(d["pivot"])) < 1e-8  # the upper pivot stays at the origin
    # The lower link leaves the plane of the upper one: the spherical joint is 3-D.
    assert np.ptp(np.asarray(qs[:, 8])) > 0.1


def test_total_energy_is_conserved_with_gravity(swinging):
    *_, d = swinging
    drift = np.max(np.abs(d["energy"] - d["energy"][0])) / np.max(d["kinetic"])
    assert drift < 1e-8


def test_free_body_falls_with_g(swinging):
    _, _, ts, qs, qds, _ = swinging
    t = ts[:, None]
    v0 = np.array([1.0, 0.5, 2.0])
    expected = np.array([0.0, 2.0, 0.0]) + v0 * t + 0.5 * np.array([0, 0, -G]) * t**2
    np.testing.assert_allclose(qs[:, FREE][:, :3], expected, rtol=0, atol=1e-8)
    np.testing.assert_allclose(qds[:, 16], v0[2] - G * ts, rtol=0, atol=1e-9)


def test_free_body_without_gravity_conserves_energy_and_angular_momentum():
    params = bench_params(gravity=0.0)
    q0, qd0 = bench_state((0.3, -0.2, 0.1), qt.from_axis_angle([1.0, 2.0, 3.0], 0.4),
                          (0.1, 0.0, -0.2), (1.0, 0.5, -0.7), pendulum_moving=False)
    ts = jnp.linspace(0.0, 10.0, N_SAVE)
    qs, qds, d = simulate_bench(params, q0, qd0, ts, 1e-12)
    # The pendulum hangs at rest without gravity, so the totals are the free body's.
    drift_e = np.max(np.abs(d["kinetic"] / d["kinetic"][0] - 1.0))
    h = d["momentum"]
    drift_h = np.max(np.linalg.norm(h - h[0], axis=1)) / np.linalg.norm(h[0])
    assert drift_e < 1e-8 and drift_h < 1e-8, (drift_e, drift_h)
    assert np.ptp(d["w_free"][:, 0]) > 0.1  # tumbling, not a steady spin
    np.testing.assert_allclose(
        qs[-1, 14:17], np.array([0.3, -0.2, 0.1]) + 10.0 * np.array([0.1, 0.0, -0.2]),
        rtol=0, atol=1e-10)


def test_spring_mass_and_torsional_bushing_frequencies():
    # Spring along x at the centre (no torque); bushing with rotational stiffness only
    # (no force): the two oscillations are independent.
    k, amp, free_length = 50.0, 0.05, 1.0  # omega = sqrt(k/m) = 5 rad/s
    k_rot, theta0 = 12.0, 1e-3  # about body z, Izz = 3: omega = 2 rad/s
    params = bench_params(gravity=0.0, spring=k, bushing=(0.0, 0.0, 0.0, 30.0, 30.0,
                                                           k_rot))
    q0, qd0 = bench_state((free_length + amp, 0.0, 0.0),
                          qt.from_axis_angle([0, 0, 1.0], theta0),
                          (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), pendulum_moving=False)
    ts = jnp.linspace(0.0, 3.0, N_SAVE)
    qs, _, _ = simulate_bench(params, q0, qd0, ts, 1e-12)
    t = np.asarray(ts)
    x_expected = free_length + amp * np.cos(np.sqrt(k / MASS) * t)
    np.testing.assert_allclose(qs[:, 14], x_expected, rtol=0, atol=1e-9)
    angle = 2.0 * np.arctan2(qs[:, 20], qs[:, 17])
    # The bushing's sin-angle measure shifts the frequency by O(theta0^2) only.
    expected = theta0 * np.cos(np.sqrt(k_rot / INERTIA[2]) * t)
    np.testing.assert_allclose(angle, expected, rtol=0, atol=1e-5 * theta0)


def test_baumgarte_stabilisation_reduces_the_drift(swinging):
    q0, qd0, ts, qs, _, d = swinging
    params = eqx.tree_at(lambda p: (p.baumgarte_alpha, p.baumgarte_beta), BENCH_PARAMS,
                         (jnp.asarray(0.0, dtype=jnp.float64),
                          jnp.asarray(0.0, dtype=jnp.float64)))
    qs_free, _, d_free = simulate_bench(params, q0, qd0, ts, SWING_TOL)
    assert _simulate_bench._cache_size() == 1  # the gains are traced: no recompilation
    assert np.max(d_free["phi"]) > 10.0 * np.max(d["phi"])
    # Same motion up to the drift (amplified over 10 s by the chaotic double pendulum).
    assert np.max(np.abs(np.asarray(qs_free) - np.asarray(qs))) < 1e-3
