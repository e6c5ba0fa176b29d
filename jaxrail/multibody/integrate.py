"""Eq. (19) integrated by diffrax: the vector field of a :class:`State` and the solve.

Both take one term, an :class:`~jaxrail.multibody.loads.AbstractLoads` (diffrax's
``args``): the system, its parameters and the loads on its bodies.
"""

import diffrax
import jax.numpy as jnp

from .equations import accelerations, element_rates, initial_element_states
from .loads import AbstractLoads, FixedLoads
from .state import State


def rhs(t, y: State, loads: AbstractLoads) -> State:
    """diffrax vector field of a :class:`State` under ``loads`` (the system, its
    parameters and the loads on its bodies).

    Where the state has a flexible track (``y.track``), ``loads.coupled(t, q, qdot,
    track)`` returns the bodies' loads (forces, torques (n, 3)) and the track's
    derivatives (the structure of ``y.track``); otherwise ``loads(t, q, qdot)``
    returns the loads. The force elements' internal states move at their kinds' rates.
    """
    q, qdot = y.q, y.qdot
    external, track_dot = loads, None
    if y.track is not None:
        forces, torques, track_dot = loads.coupled(t, q, qdot, y.track)
        external = FixedLoads(forces, torques)
    system, params = loads.system, loads.system_params
    qddot, _ = accelerations(system, params, t, q, qdot, external, y.elements)
    return State(qdot, qddot, track_dot, element_rates(system, params, q, qdot, y.elements))


def simulate_system(loads: AbstractLoads, q0, qdot0, t1, dt0=1e-3, saveat=None, rtol=1e-8,
                    atol=1e-8, solver=None, t0=0.0, max_steps=100_000, adjoint=None,
                    throw=True, stepsize_controller=None, event=None, progress_meter=None,
                    track0=None, elements0=None):
    """Integrate eq. (19) of ``loads``' system with diffrax from (q0, qdot0) at t0 [s] to
    t1 [s]; ``loads``: e.g. ``SystemLoads(system, params)`` or a
    :class:`jaxrail.vehicles.VehicleLoads`.

    Returns diffrax's Solution, with ys a :class:`State` (q (..., 7 n), qdot (..., 7
    n), ...) at `saveat` (default: t1 only). ``track0``: a flexible track's rails at t0
    (a pytree of arrays, integrated with the bodies through ``loads.coupled``,
    :func:`rhs`); ``elements0``: the force elements' internal states at t0 (default:
    at rest at q0, :func:`initial_element_states`). solver defaults to Tsit5;
    stepsize_controller to a PIDController with rtol, atol (pass
    diffrax.ConstantStepSize() for fixed steps dt0); adjoint to
    RecursiveCheckpointAdjoint (reverse-mode AD works). event and progress_meter are
    passed to diffrax (a terminating diffrax.Event, a progress meter).
    """
    q0 = jnp.asarray(q0, dtype=jnp.float64)
    if elements0 is None:
        elements0 = initial_element_states(loads.system, loads.system_params, q0)
    y0 = State.of(q0, qdot0, track0, elements0)
    solver = diffrax.Tsit5() if solver is None else solver
    # Tsit5 is first-same-as-last: its state is the last stage. Given at the start,
    # the first step does not evaluate its first stage again at each rejected attempt
    # (diffrax's own start does), so every attempt costs 6 right-hand sides.
    solver_state = ((jnp.asarray(False), rhs(t0, y0, loads)) if type(solver) is diffrax.Tsit5
                    else None)
    return diffrax.diffeqsolve(
        diffrax.ODETerm(rhs),
        solver,
        t0,
        t1,
        dt0,
        y0,
        args=loads,
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
