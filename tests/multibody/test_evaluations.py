"""The right-hand sides and load Jacobians an integration evaluates, counted by a load
that counts its own calls, against :func:`jaxrail.simulation.evaluations_per_step` and
IMEX's :class:`~jaxrail.multibody.imex.JacobianCounter`, which a simulation's
``rhs_evaluations`` and ``jacobian_evaluations`` come from: IMEX (KenCarp3 and
KenCarp5, a new Jacobian every step or every third accepted one) and Tsit5, with
step-size control rejecting steps."""

import diffrax
import jax
import jax.numpy as jnp
import pytest

import jaxrail.multibody as mb
from jaxrail.multibody.imex import IMEX, JacobianCounter
from jaxrail.simulation import evaluations_per_step

MASS = 2.0
BODY, BODY_PARAMS = mb.build_system([mb.RigidBody("block", MASS, (0.1, 0.2, 0.3))])
CALLS = {"loads": 0, "linearised": 0}


def _count(name):
    def add():
        CALLS[name] += 1
    jax.debug.callback(add, ordered=True)


class CountingSpring(mb.AbstractLoads):
    """A stiff damped spring along global x on BODY (per unit mass k [1/s^2], c [1/s])
    that counts its evaluations: as loads (a right-hand side) and linearised (a
    right-hand side with its Jacobian)."""

    k: float = 1e4
    c: float = 2000.0
    system: mb.System = BODY
    system_params: mb.SystemParams = BODY_PARAMS

    def _loads(self, q, qdot):
        force = -MASS * (self.k * q[0] + self.c * qdot[0])
        return jnp.zeros((1, 3)).at[0, 0].set(force), jnp.zeros((1, 3))

    def __call__(self, t, q, qdot):
        _count("loads")
        return self._loads(q, qdot)

    def linearised(self, t, q, qdot, track=None, jacobian=True):
        """The loads, and where ``jacobian`` (a bool, maybe traced) holds their Jacobian:
        counted as a Jacobian evaluation there, as a right-hand side elsewhere."""
        def with_jacobian():
            _count("linearised")
            block = jnp.zeros((1, 7, 14)).at[0, 0, 0].set(-MASS * self.k)
            return block.at[0, 0, 7].set(-MASS * self.c)

        def without():
            _count("loads")
            return jnp.zeros((1, 7, 14))

        def when(flags):  # IMEX's flags: one, or a tuple tested one inside the other
            if not flags:
                return with_jacobian()
            return jax.lax.cond(flags[0], lambda: when(flags[1:]), without)

        block = when(jacobian if isinstance(jacobian, tuple) else (jacobian,))
        return (*self._loads(q, qdot), (0,), block)


@pytest.mark.parametrize("solver", [IMEX("KenCarp5"), IMEX("KenCarp3"),
                                    IMEX("KenCarp5", jacobian_every=3), diffrax.Tsit5()],
                         ids=["KenCarp5", "KenCarp3", "KenCarp5-every-3", "Tsit5"])
def test_counted_evaluations_equal_the_reported_ones(solver):
    CALLS.update(loads=0, linearised=0)
    q0 = jnp.array([1.0, 0, 0, 1.0, 0, 0, 0])
    imex = isinstance(solver, IMEX)
    controller = diffrax.PIDController(rtol=1e-8, atol=1e-10)
    if imex:
        controller = JacobianCounter(controller, solver.jacobian_every)
    # a first step far too long for the tolerance: the controller rejects steps
    sol = jax.jit(lambda q: mb.simulate_system(
        CountingSpring(), q, jnp.zeros(7), 0.05, dt0=0.02,
        saveat=diffrax.SaveAt(t1=True, controller_state=imex), solver=solver,
        stepsize_controller=controller, throw=False, max_steps=10_000))(q0)
    jax.effects_barrier()
    steps, rejected = int(sol.stats["num_steps"]), int(sol.stats["num_rejected_steps"])
    assert sol.result == diffrax.RESULTS.successful and rejected >= 1 and steps >= 5
    per_step, at_start = evaluations_per_step(solver)
    assert CALLS["loads"] + CALLS["linearised"] == per_step * steps + at_start
    if not imex:
        assert CALLS["linearised"] == 0
        return
    assert CALLS["linearised"] == int(sol.controller_state[-1])
    if solver.jacobian_every == 1:
        assert CALLS["linearised"] == steps
    else:  # fewer than one per attempt, rejected attempts included
        accepted = int(sol.stats["num_accepted_steps"])
        assert accepted / solver.jacobian_every <= CALLS["linearised"] < steps


def test_an_unknown_solver_has_no_count():
    assert evaluations_per_step(diffrax.Dopri5()) == (-1, -1)


def test_under_vmap_the_jacobian_stays_at_the_first_stage():
    """In a batch each member's J has its own age, so whether to refresh is a batched
    flag, and a ``lax.cond`` on it runs both branches. IMEX tests its stage first
    (unbatched), so the Jacobian runs once per step attempt of the batch, not at all 8
    stages. Each counted call is one batched evaluation."""
    CALLS.update(loads=0, linearised=0)
    q0 = jnp.array([[1.0, 0, 0, 1.0, 0, 0, 0], [0.5, 0, 0, 1.0, 0, 0, 0]])
    sol = jax.jit(jax.vmap(lambda q: mb.simulate_system(
        CountingSpring(), q, jnp.zeros(7), 0.05, dt0=0.02, saveat=diffrax.SaveAt(t1=True),
        solver=IMEX(jacobian_every=3),
        stepsize_controller=diffrax.PIDController(rtol=1e-8, atol=1e-10), throw=False,
        max_steps=10_000)))(q0)
    jax.effects_barrier()
    attempts = int(jnp.max(sol.stats["num_steps"]))  # the batch's loop runs them all
    assert attempts >= 5
    assert CALLS["linearised"] == attempts
    assert CALLS["loads"] == 8 * attempts  # the other 7 stages, and the first's select
