"""Force elements with internal states (Maxwell damper, air spring) against closed forms:
the complex stiffness under a sinusoid, the characteristic's points, and the energy
balance of a system that carries them in its State."""

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrail.multibody as mb
from jaxrail.multibody.forces import FORCE_KINDS

X0, OMEGA = 2e-3, 2.0 * np.pi * 1.5  # [m], [rad/s]: a yaw damper near hunting frequency


def _one(kind, spec):
    """The traced params of one element of ``kind`` (leading axis dropped)."""
    return jax.tree.map(lambda x: x[0], FORCE_KINDS[kind].params([spec], "test"))


def _steady_force(kind, e, deformation, periods=12):
    """(in-phase, quadrature) parts [N] of the element's force under the prescribed
    deformation s(t) = deformation(x0 sin(w t)), fitted over the last two periods after
    ``periods`` (the transient gone), from the element's own law and rate."""
    law, rate, initial = FORCE_KINDS[kind].law, FORCE_KINDS[kind].rate, FORCE_KINDS[kind].initial
    column = 0 if kind == "maxwell_damper" else 2

    def field(t, z, _):
        return rate(deformation(X0 * jnp.sin(OMEGA * t)), None, e, z)

    t1 = periods * 2.0 * np.pi / OMEGA
    ts = jnp.linspace(t1 - 4.0 * np.pi / OMEGA, t1, 801)
    sol = diffrax.diffeqsolve(diffrax.ODETerm(field), diffrax.Tsit5(), 0.0, t1, 1e-3,
                              initial(deformation(0.0), e), saveat=diffrax.SaveAt(ts=ts),
                              stepsize_controller=diffrax.PIDController(rtol=1e-12, atol=1e-14),
                              max_steps=200_000)
    force = jax.vmap(lambda t, z: law(deformation(X0 * jnp.sin(OMEGA * t)), None, e, z)[column]
                     )(ts, sol.ys)
    static = law(deformation(0.0), None, e, initial(deformation(0.0), e))[column]
    basis = np.stack([np.sin(OMEGA * np.asarray(ts)), np.cos(OMEGA * np.asarray(ts))], axis=1)
    (a, b), *_ = np.linalg.lstsq(basis, np.asarray(force) - float(static), rcond=None)
    return a, b


def _check_complex_stiffness(a, b, expected):
    measured = complex(a, b) / X0
    assert abs(abs(measured) / abs(expected) - 1.0) < 1e-4
    assert abs(np.angle(measured) - np.angle(expected)) < 1e-4


def test_maxwell_damper_has_the_complex_stiffness_of_a_spring_and_damper_in_series():
    k_s, c = 6.0e6, 4.0e5  # yaw damper: N/m, N s/m (time constant 67 ms)
    e = _one("maxwell_damper", mb.MaxwellDamper(0, 1, (0, 0, 0), (0, 0, 0), k_s, 0.5,
                                                damping=c))
    a, b = _steady_force("maxwell_damper", e, lambda x: jnp.asarray([0.5 + x]))
    expected = k_s * 1j * OMEGA * c / (k_s + 1j * OMEGA * c)
    _check_complex_stiffness(a, b, expected)
    # neither a pure spring nor a pure damper at this frequency
    assert 0.2 < np.angle(expected) < 1.4


def test_air_spring_has_the_reservoir_frequency_dependence():
    k1, k2, c = 3.0e5, 4.0e5, 4.0e4  # N/m, N/m, N s/m
    spec = mb.AirSpring(0, 1, (0, 0, 0), (0, 0, 0), k1, k2, c, 1.2e5, 1.2e5, preload=-8e4)
    e = _one("air_spring", spec)
    a, b = _steady_force("air_spring", e, lambda x: jnp.stack([0.0, 0.0, x]))
    expected = k1 + k2 * 1j * OMEGA * c / (k2 + 1j * OMEGA * c)
    _check_complex_stiffness(a, b, expected)
    # laterally the bellows' shear stiffness, no frequency dependence
    law = FORCE_KINDS["air_spring"].law
    s = jnp.asarray([0.0, 1e-3, 0.0])
    assert float(law(s, None, e, jnp.zeros(1))[1]) == pytest.approx(1.2e5 * 1e-3, rel=1e-14)


def test_blow_off_characteristic_is_exact_at_the_table_points():
    """A yaw damper with blow-off: 400 kN s/m up to 8 kN, 40 kN s/m beyond. Under a
    constant force the damper's rate is the table's velocity at the table's forces, and
    monotone between them."""
    v = np.array([-0.1, -0.02, 0.0, 0.02, 0.1])
    f = np.array([-11.2e3, -8e3, 0.0, 8e3, 11.2e3])
    e = _one("maxwell_damper", mb.MaxwellDamper(0, 1, (0, 0, 0), (0, 0, 0), 6e6, 0.5,
                                                velocities=v, forces=f))
    rate = FORCE_KINDS["maxwell_damper"].rate
    for force, velocity in zip(f, v):
        z = jnp.asarray([-force / 6e6])  # spring deflection s - L0 - z = force / k_s
        np.testing.assert_allclose(rate(jnp.asarray([0.5]), None, e, z)[0], velocity,
                                   rtol=1e-12, atol=1e-15)
    forces = jnp.linspace(-14e3, 14e3, 301)
    rates = jax.vmap(lambda F: rate(jnp.asarray([0.5]), None, e, jnp.asarray([-F / 6e6]))[0])(
        forces)
    assert np.all(np.diff(np.asarray(rates)) > 0.0)


def test_a_damper_table_that_is_not_monotone_is_refused():
    with pytest.raises(ValueError, match="yaw_damper.*strictly increasing"):
        FORCE_KINDS["maxwell_damper"].params(
            [mb.MaxwellDamper(0, 1, (0, 0, 0), (0, 0, 0), 6e6, 0.5, velocities=[-0.1, 0, 0.1],
                              forces=[-8e3, 0.0, -1e3], name="yaw_damper")], "force")


def _oscillator(kind_element):
    """A 1000 kg block on a vertical spring (no damping) and ``kind_element``."""
    block = mb.RigidBody("block", 1000.0, (10.0, 10.0, 10.0))
    spring = mb.SpringDamper("ground", "block", (0, 0, 1.0), (0, 0, 0), 4e5, 1.0)
    return mb.build_system([block], forces=[spring, kind_element])


@pytest.mark.parametrize("element", [
    mb.MaxwellDamper("ground", "block", (0, 0, 1.0), (0, 0, 0), 2e6, 1.0, damping=2e4),
    mb.AirSpring("ground", "block", (0, 0, 0), (0, 0, 0), 1e5, 3e5, 1e4, 5e4, 5e4),
], ids=["maxwell", "air_spring"])
def test_energy_stored_plus_dissipated_is_conserved(element):
    """The block starts 5 mm up and oscillates: kinetic energy, the energy stored in the
    springs (the internal states' included) and the work the dampers dissipated add up
    to the start's within 1e-6 of the energy that moves (State through simulate_system,
    rhs, potential_energy and dissipated_power)."""
    system, params = _oscillator(element)
    q0 = jnp.array([0.0, 0.0, 0.005, 1.0, 0.0, 0.0, 0.0])
    qdot0 = jnp.zeros(7)
    elements0 = mb.initial_element_states(system, params, jnp.array([0, 0, 0, 1.0, 0, 0, 0]))
    ts = jnp.linspace(0.0, 0.5, 4001)
    sol = mb.simulate_system(mb.SystemLoads(system, params), q0, qdot0, 0.5, dt0=1e-4,
                             rtol=1e-11, atol=1e-13, saveat=diffrax.SaveAt(ts=ts),
                             elements0=elements0, max_steps=400_000)
    y = sol.ys
    kinetic = jax.vmap(lambda q, v: mb.kinetic_energy(system, params, q, v))(y.q, y.qdot)
    stored = jax.vmap(lambda q, z: mb.potential_energy(system, params, q, z))(y.q, y.elements)
    power = jax.vmap(lambda q, v, z: mb.dissipated_power(system, params, q, v, z))(
        y.q, y.qdot, y.elements)
    # the dissipated work by Simpson's rule, at every second output
    p, dt = np.asarray(power), float(ts[1] - ts[0])
    pairs = dt / 3.0 * (p[:-2:2] + 4.0 * p[1:-1:2] + p[2::2])
    dissipated = np.concatenate([[0.0], np.cumsum(pairs)])
    total = np.asarray(kinetic + stored)[::2] + dissipated
    moving = float(stored[0] - jnp.min(stored))
    assert float(dissipated[-1]) > 0.3 * moving  # the damper did work
    assert np.max(np.abs(total - total[0])) < 1e-6 * moving
    assert y.elements["maxwell_damper" if "maxwell" in element.kind else "air_spring"].shape \
        == (ts.size, 1, 1)


def test_gradient_through_the_internal_state_matches_central_differences():
    """d(final height)/d(damping) and d/d(series stiffness) of the block under jit and
    grad, against central differences; under vmap over two dampings, the single runs."""
    element = mb.MaxwellDamper("ground", "block", (0, 0, 1.0), (0, 0, 0), 2e6, 1.0,
                               damping=2e4)
    system, params = _oscillator(element)
    q0 = jnp.array([0.0, 0.0, 0.005, 1.0, 0.0, 0.0, 0.0])
    z0 = mb.initial_element_states(system, params, jnp.array([0, 0, 0, 1.0, 0, 0, 0]))

    def height(c, k):
        e = params.forces["maxwell_damper"]  # linear: velocity F / c at force F
        scaled = type(e)(e.point_i, e.point_j, k[None], e.free_length, e.forces,
                         e.velocities / c * 2e4, e.slopes / c * 2e4)
        p = type(params)(params.bodies, params.joints, {**params.forces,
                                                         "maxwell_damper": scaled},
                         params.gravity, params.baumgarte_alpha, params.baumgarte_beta)
        sol = mb.simulate_system(mb.SystemLoads(system, p), q0, jnp.zeros(7), 0.05,
                                 dt0=1e-4, rtol=1e-12, atol=1e-14, elements0=z0,
                                 max_steps=100_000)
        return sol.ys.q[-1, 2]

    c, k = jnp.float64(2e4), jnp.float64(2e6)
    grad = jax.jit(jax.grad(height, argnums=(0, 1)))(c, k)
    for i, (x, h) in enumerate(((c, 2.0), (k, 200.0))):
        shift = lambda d: (c + d, k) if i == 0 else (c, k + d)  # noqa: E731
        fd = (height(*shift(h)) - height(*shift(-h))) / (2.0 * h)
        assert abs(float(grad[i]) / float(fd) - 1.0) < 1e-5
    batched = jax.jit(jax.vmap(lambda c: height(c, k)))(jnp.array([2e4, 3e4]))
    np.testing.assert_allclose(batched[1], height(jnp.float64(3e4), k), rtol=1e-12)
