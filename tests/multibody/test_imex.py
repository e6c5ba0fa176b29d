"""The IMEX integrator (jaxrail.multibody.imex) against analytic solutions, the dense
augmented solve and a brute-force Jacobian.

A stiff damped oscillator (one free body, damping c/m = 2000 1/s, stiffness k/m = 1e4
1/s^2: eigenvalues -5.01 and -1995 1/s) is solved exactly; at 10 ms steps the
explicit method blows up and IMEX follows the analytic solution. With loads that are
not stiff (the default ``linearised``) IMEX is the explicit KenCarp5 tableau and
converges at fifth order.
"""

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrail.multibody as mb
from jaxrail.multibody.imex import IMEX, StiffJacobian, stiff_jacobian
from jaxrail.multibody.equations import _augmented_solve, _right_hand_sides

MASS = 2.0
BODY, BODY_PARAMS = mb.build_system([mb.RigidBody("block", MASS, (0.1, 0.2, 0.3))])


class Spring(mb.AbstractLoads):
    """Force -k x - c v along global x on body 0 of BODY (traced k, c [per unit mass]),
    not stiff for IMEX (the default ``linearised``)."""

    k: jax.Array
    c: jax.Array
    system: mb.System = BODY
    system_params: mb.SystemParams = BODY_PARAMS

    def __call__(self, t, q, qdot):
        force = -MASS * (self.k * q[0] + self.c * qdot[0])
        return jnp.zeros((1, 3)).at[0, 0].set(force), jnp.zeros((1, 3))


class StiffSpring(Spring):
    """The same force with its Jacobian for IMEX."""

    def linearised(self, t, q, qdot, track=None, jacobian=True):  # whatever `jacobian` says
        forces, torques = self(t, q, qdot)
        block = jnp.zeros((1, 7, 14)).at[0, 0, 0].set(-MASS * self.k)
        return forces, torques, (0,), block.at[0, 0, 7].set(-MASS * self.c)


def run(loads, h, t1=1.0, solver=None, n=11):
    q0 = jnp.array([1.0, 0, 0, 1.0, 0, 0, 0])
    sol = mb.simulate_system(loads, q0, jnp.zeros(7), t1, dt0=h,
                             saveat=diffrax.SaveAt(ts=jnp.linspace(0.0, t1, n)),
                             solver=IMEX() if solver is None else solver,
                             stepsize_controller=diffrax.ConstantStepSize(), throw=False,
                             max_steps=10_000)
    return sol.ys.q[:, 0]


def exact(k, c, t, x0=1.0):
    """x(t) of x'' + c x' + k x = 0 from x0 at rest (real roots)."""
    root = np.sqrt(c * c - 4 * k)
    fast, slow = (-c - root) / 2, (-c + root) / 2
    a = x0 * fast / (fast - slow)
    return a * np.exp(slow * t) + (x0 - a) * np.exp(fast * t)


def test_stiff_oscillator_at_long_steps_follows_the_exact_solution():
    k, c = 1e4, 2000.0
    t = np.linspace(0.0, 1.0, 11)
    x = np.asarray(run(StiffSpring(jnp.asarray(k), jnp.asarray(c)), 1e-2))
    assert np.max(np.abs(x - exact(k, c, t))) < 1e-4
    explicit = np.asarray(run(Spring(jnp.asarray(k), jnp.asarray(c)), 1e-2,
                              solver=diffrax.Tsit5()))
    assert not np.all(np.abs(explicit) < 10.0)  # hλ = -20: the explicit method blows up


def test_without_jacobian_converges_at_fifth_order():
    k, c = 400.0, 0.0  # an undamped oscillator, 3.2 Hz
    errors = []
    for h in (1e-2, 5e-3):
        x = np.asarray(run(Spring(jnp.asarray(k), jnp.asarray(c)), h))
        errors.append(np.max(np.abs(x - np.cos(20.0 * np.linspace(0.0, 1.0, 11)))))
    assert errors[0] / errors[1] > 2.0 ** 4.5


@pytest.mark.parametrize("solver", [IMEX(), IMEX(jacobian_every=3)], ids=["every-step", "kept"])
def test_gradient_through_a_stiff_run_matches_central_differences(solver):
    """Reverse mode through 100 fixed steps; with the Jacobian kept for 3 steps too (it
    is then carried in the solver's state)."""
    def final(c):
        return run(StiffSpring(jnp.asarray(1e4), c), 1e-2, solver=solver)[-1]

    grad = jax.grad(final)(jnp.asarray(2000.0))
    step = 1.0
    fd = (final(jnp.asarray(2000.0 + step)) - final(jnp.asarray(2000.0 - step))) / (2 * step)
    assert float(grad) == pytest.approx(float(fd), rel=1e-4)
    # x(1) ~ exp(lambda) with the slow root lambda ~ -k / c: dx/dc ~ x k / c^2
    assert float(grad) == pytest.approx(float(final(jnp.asarray(2000.0))) * 1e4 / 2000.0**2,
                                        rel=0.02)


def test_stiff_jacobian_of_a_jointed_system_matches_the_dense_solve():
    """acceleration_response: the accelerations per unit body load equal the dense
    augmented solve's response to the same loads (two bodies on a spherical joint)."""
    system, params = mb.build_system(
        [mb.RigidBody("a", 3.0, (0.2, 0.3, 0.4)), mb.RigidBody("b", 1.0, (0.05, 0.1, 0.2))],
        joints=[mb.Spherical("a", "b", (0.0, 0.0, -0.3), (0.0, 0.0, 0.2))],
        gravity=(0.0, 0.0, -9.81))
    p = mb.quaternion.from_axis_angle(jnp.array([0.3, 0.5, 0.8]), jnp.asarray(0.4))
    q = jnp.concatenate([jnp.zeros(3), p, jnp.array([0.1, 0.0, -0.5]), p])
    q, qdot = mb.consistent_initial_conditions(system, params, q, jnp.linspace(0.1, 1.4, 14))
    blocks = jax.random.normal(jax.random.PRNGKey(0), (1, 7, 5))
    response = mb.acceleration_response(system, params, q, qdot, (1,), blocks)
    top, bottom, phi_q = _right_hand_sides(system, params, 0.0, q, qdot, None)
    mass = mb.mass_matrix(system, params, q)
    base = _augmented_solve(mass, phi_q, top, bottom)[0]
    for m in range(5):
        load = jnp.zeros(14).at[7:].set(blocks[0, :, m])
        pushed = _augmented_solve(mass, phi_q, top + load, bottom)[0]
        np.testing.assert_allclose(response[:, 0, m], pushed - base, atol=1e-9)


def test_stiff_jacobian_of_loads_that_are_not_stiff_is_zero():
    q = jnp.array([1.0, 0, 0, 1.0, 0, 0, 0])
    (_, qddot, _), jac = stiff_jacobian(0.0, mb.State.of(q, jnp.zeros(7)),
                                        Spring(jnp.asarray(4.0), jnp.asarray(0.0)))
    assert jac.columns == () and float(qddot[0]) == pytest.approx(-4.0)


class BrokenJacobian(StiffSpring):
    """The stiff spring with a Jacobian entry that is not finite."""

    def linearised(self, t, q, qdot, track=None, jacobian=True):
        forces, torques, bodies, block = super().linearised(t, q, qdot)
        return forces, torques, bodies, block.at[0, 0, 0].set(jnp.nan)


@pytest.mark.parametrize("controller", ["constant", "pid"])
def test_a_failed_factorisation_ends_the_run_with_its_result(controller):
    """The step's matrix I - h gamma J is not finite: the run stops at its start with
    diffrax's ``singular`` result, whatever the step-size controller (an adaptive one
    would otherwise shrink the step without end)."""
    step = (diffrax.ConstantStepSize() if controller == "constant"
            else diffrax.PIDController(rtol=1e-6, atol=1e-9))
    q0 = jnp.array([1.0, 0, 0, 1.0, 0, 0, 0])
    sol = mb.simulate_system(BrokenJacobian(jnp.asarray(1e4), jnp.asarray(2000.0)), q0,
                             jnp.zeros(7), 1.0, dt0=1e-2, saveat=diffrax.SaveAt(t1=True),
                             solver=IMEX(), stepsize_controller=step, throw=False,
                             max_steps=10_000)
    assert sol.result == diffrax.RESULTS.singular
    assert int(sol.stats["num_steps"]) == 1
    healthy = run(StiffSpring(jnp.asarray(1e4), jnp.asarray(2000.0)), 1e-2)
    assert np.isfinite(np.asarray(healthy)).all()  # the same run with a finite Jacobian


def test_a_failed_step_keeps_finite_outputs_before_it():
    """The step whose Jacobian is not finite is kept as its start: the states saved up
    to and within it (Hermite output from its start) stay finite, so that a run that
    fails keeps its results so far."""
    q0 = jnp.array([1.0, 0, 0, 1.0, 0, 0, 0])
    sol = mb.simulate_system(BrokenJacobian(jnp.asarray(1e4), jnp.asarray(2000.0)), q0,
                             jnp.zeros(7), 1.0, dt0=1e-2,
                             saveat=diffrax.SaveAt(ts=jnp.array([0.0, 0.005, 0.01])),
                             solver=IMEX(), stepsize_controller=diffrax.ConstantStepSize(), throw=False,
                             max_steps=10)
    assert sol.result == diffrax.RESULTS.singular
    assert np.isfinite(np.asarray(sol.ys.q)).all() and np.isfinite(np.asarray(sol.ys.qdot)).all()


@pytest.mark.parametrize("entry", [0.0, 1.0])
def test_a_singular_step_matrix_is_not_factored_ok(entry):
    """I - hg J with a zero pivot (hg A_v = 1 on a one-column J) has no finite inverse;
    the same J at a shorter step has one."""
    hg = 1e-3
    jac = StiffJacobian((0,), jnp.zeros((1, 1)), jnp.full((1, 1), 1.0 / hg))
    factored = jac.factor(hg * (1.0 - 0.5 * entry))
    assert bool(jac.factored_ok(factored)) == (entry == 1.0)
