"""The solve: the traceable core of a run (:func:`solve`). From the static equilibrium
or a given state, diffrax integrates eq. (19) with Baumgarte stabilisation under the
wheel-rail loads until ``t1`` or a stop (derailment, a non-finite state), and the
outputs are recomputed from the saved states (:mod:`.outputs`).

Solver: Tsit5 with a PID step-size controller by default, or the IMEX method of
:mod:`jaxrail.multibody.imex` (``SolverOptions(integrator="imex")``); the measurements that
chose them are in docs/simulation.md.
"""

import diffrax
import jax
import jax.numpy as jnp

from .._time_report import TimeReportingMeter
from ..multibody import State, simulate_system
from ..multibody import initial_state as system_initial_state
from ..multibody.imex import IMEX, JacobianCounter
from ..vehicles.initial import initial_state
from ..vehicles.loads import VehicleLoads, resolve_contact_model
from ..vehicles.vehicle import Vehicle, VehicleParams
from .options import DerailmentLimits, SolverOptions
from .outputs import simulation_result, wheelset_track_coordinates


def evaluations_per_step(solver) -> tuple[int, int]:
    """``(right-hand sides per step, right-hand sides at the start)`` of a step-size
    attempt, accepted or rejected, of ``solver``:

    - :class:`~jaxrail.multibody.imex.IMEX`: s (its stages; the first comes with the
      load Jacobian where the step evaluates one, from one contact evaluation), none
      at the start; its load Jacobians are counted by
      :class:`~jaxrail.multibody.imex.JacobianCounter`;
    - diffrax's Tsit5, first-same-as-last: 6 per step and 1 at the start.

    ``(-1, -1)`` for another solver. Counted in ``tests/multibody/test_evaluations.py``."""
    if isinstance(solver, IMEX):
        return solver.stages, 0
    if type(solver) is diffrax.Tsit5:
        return 6, 1
    return -1, -1


def _stop_events(vehicle, params, track, limits, rest_height):
    """The terminating diffrax Event of a run: (derailed, non-finite state)."""
    def derailed(t, y, args, **kwargs):
        deflection = None if y.track is None else y.track[0]
        lateral, _, _, heights, irregularity = wheelset_track_coordinates(
            vehicle, params, track, y.q, y.qdot, deflection)
        lifted = jnp.any(heights - rest_height > limits.lift)
        off = jnp.any(jnp.abs(lateral - irregularity[:, 0]) > limits.lateral)
        return lifted | off

    def not_finite(t, y, args, **kwargs):
        return ~jnp.all(jnp.stack([jnp.all(jnp.isfinite(x)) for x in jax.tree.leaves(y)]))

    return diffrax.Event((derailed, not_finite))


def _starts_derailed(limits, lateral0, irregularity0, misalignment):
    """Whether a run starts beyond the lateral limit: its initial wheelsets (lateral0
    (W,) [m] from the design centreline, less the alignment of ``irregularity0`` (W, 4)
    [m]: from the irregular track's centre) are, or the start is not finite and the
    misalignment asked for is beyond it (the static equilibrium of a wheel off its rail
    does not exist)."""
    lateral0 = lateral0 - irregularity0[:, 0]
    unknown = ~jnp.all(jnp.isfinite(lateral0))
    return (jnp.any(jnp.abs(lateral0) > limits.lateral)
            | (unknown & (jnp.abs(misalignment) > limits.lateral)))


def _integrate(loads, start, rest_heights, t1, ts, options, limits, solver, adjoint,
               report=False):
    """diffrax's Solution of eq. (19) under ``loads`` (:class:`VehicleLoads`: the
    vehicle, its parameters, the track) from the :class:`State` ``start`` at 0 to t1
    [s] with ``solver``, saved at ``ts``, stopped by the derailment event (a flexible
    track's rails and the elements' internal states are integrated with the bodies);
    ``report``: the time reached to the host, up to 1000 times a run
    (:class:`TimeReportingMeter`).
    With IMEX the controller counts its load Jacobians (:class:`JacobianCounter`, the
    saved controller state)."""
    controller, dt0 = options.controller()
    counting = isinstance(solver, IMEX)
    if counting:
        controller = JacobianCounter(controller, solver.jacobian_every)
    return simulate_system(
        loads, start.q, start.qdot, t1, dt0=dt0,
        saveat=diffrax.SaveAt(ts=ts, controller_state=counting), rtol=options.rtol,
        atol=options.atol, solver=solver,
        max_steps=options.max_steps, adjoint=adjoint, throw=False,
        stepsize_controller=controller,
        event=_stop_events(loads.vehicle, loads.params, loads.track, limits, rest_heights),
        track0=start.track, elements0=start.elements,
        progress_meter=TimeReportingMeter(t1) if report else None)


def _evaluations(solver, sol):
    """(right-hand sides, load Jacobians) of the step attempts of ``solver`` in the
    diffrax Solution ``sol`` of :func:`_integrate` (:func:`evaluations_per_step`; IMEX's
    Jacobians from its :class:`JacobianCounter`), -1 each for a solver it does not
    know."""
    per_step, at_start = evaluations_per_step(solver)
    if per_step < 0:
        return jnp.asarray(-1), jnp.asarray(-1)
    jacobians = sol.controller_state[-1] if isinstance(solver, IMEX) else jnp.asarray(0)
    return sol.stats["num_steps"] * per_step + at_start, jacobians


def _start(vehicle, params, track, speed, misalignment, s0, initial, model):
    """The :class:`State` a run starts from: ``initial``, or the static equilibrium."""
    if initial is None:
        initial = initial_state(vehicle, params, track, speed, misalignment, s0, model)
    return as_state(vehicle, params, track, initial)


def as_state(vehicle, params, track, initial) -> State:
    """``initial`` as a float64 :class:`State`, checked against the track: a flexible
    track needs its rails' state, a rigid one has none. A pair ``(q0, qdot0)`` on rigid
    rails is taken as the State with the force elements at rest."""
    if not isinstance(initial, State):
        q0, qdot0 = initial
        initial = system_initial_state(vehicle.system, params.system, q0, qdot0)
    flexible = getattr(track, "support", None) is not None
    if (initial.track is not None) != flexible:
        raise ValueError(f"initial must {'' if flexible else 'not '}hold the rails' state "
                         f"(State.track) on {'a flexible track' if flexible else 'rigid rails'}")
    return State.of(initial.q, initial.qdot, initial.track, initial.elements)


def _saved_states(sol, start: State) -> State:
    """The states diffrax saved, the first output (t = 0) the ``start`` itself, so that
    a run stopped at once keeps it."""
    return jax.tree.map(lambda saved, x0: saved.at[0].set(x0), sol.ys, start)


def solve(vehicle: Vehicle, params: VehicleParams, track, t1, speed, misalignment=0.0,
          s0=None, options: SolverOptions = SolverOptions(),
          limits: DerailmentLimits | None = None, solver=None, adjoint=None,
          initial=None, contact_model=None, report_progress=False, drive=None):
    """The traceable core of :func:`~jaxrail.simulation.simulate` (jit, vmap and grad
    it): returns a :class:`~jaxrail.simulation.SimulationResult` without host timings.
    ``t1`` [s], ``speed`` [m/s] and ``misalignment`` [m] may be traced. ``initial``: a
    :class:`~jaxrail.multibody.State` (or on rigid rails ``(q0, qdot0)``) to start from
    instead of the static equilibrium (:func:`jaxrail.vehicles.initial_state`); wheel
    lifts and vertical displacements are measured from the initial state.
    ``contact_model``: :mod:`jaxrail.vehicles.loads` (default the paper's search).
    ``options.progress`` is not used here (:func:`~jaxrail.simulation.simulate` draws
    the bar). ``limits``: :class:`DerailmentLimits` (default ones). ``report_progress``:
    pass the time reached to the host (:mod:`jaxrail._time_report`; it changes no
    value), as :func:`~jaxrail.simulation.simulate` does for its progress bar.
    ``drive``: a :class:`~jaxrail.vehicles.drive.SpeedDrive` holding the speed to its
    programme (default None: the vehicle coasts)."""
    limits = DerailmentLimits() if limits is None else limits
    loads = VehicleLoads(vehicle, params, track, resolve_contact_model(contact_model), drive)
    start = _start(vehicle, params, track, speed, misalignment, s0, initial, loads.model)
    lateral0, _, _, rest_heights, irregularity0 = wheelset_track_coordinates(
        vehicle, params, track, start.q, start.qdot, None if start.track is None
        else start.track[0])
    ts = jnp.linspace(0.0, t1, options.n_outputs)
    solver = options.solver() if solver is None else solver
    sol = _integrate(loads, start, rest_heights, t1, ts, options, limits, solver, adjoint,
                     report_progress)
    # a state that only turned non-finite is not derailed: diffrax's event_occurred
    # result makes the status "failed"
    derailed = sol.event_mask[0] | _starts_derailed(limits, lateral0, irregularity0,
                                                    misalignment)
    return simulation_result(vehicle, params, track, loads.model, start, ts,
                             _saved_states(sol, start), sol.result, derailed,
                             sol.stats["num_steps"], sol.stats["num_accepted_steps"],
                             sol.stats["num_rejected_steps"],
                             _evaluations(solver, sol), drive)
