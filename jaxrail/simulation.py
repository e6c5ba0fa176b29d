"""Simulation of a vehicle on a track: initial equilibrium, integration, outputs.

``simulate(vehicle, params, track, t1, speed=..., misalignment=...)`` puts the vehicle
at rest on its wheels (:func:`jaxrail.vehicles.initial_state`), integrates the
equations of motion (eq. 19 with Baumgarte stabilisation) with the wheel-rail loads of
every wheelset by diffrax, and returns a :class:`SimulationResult`: body states at the
output times, the contact details of every wheel and patch recomputed from them, and a
status. A run stops early, keeping its results so far, when a wheel derails (a
wheelset moves sideways or a wheel rises beyond the limits of
:class:`DerailmentLimits`) or the integration fails (non-finite state, step size
collapse, too many steps).

Solver: Tsit5 with a PID step-size controller by default, or the IMEX method of
:mod:`jaxrail.multibody.imex` (``SolverOptions(integrator="imex")``); the measurements that
chose them are in docs/simulation.md.
"""

import dataclasses
import time
import warnings

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._compiler import compile_function
from ._lru import LruCache
from ._progress import SimulatedTimeBar
from ._time_report import TimeReportingMeter, listening
from .multibody import FixedLoads, State, accelerations, constraints, simulate_system
from .multibody import initial_state as system_initial_state
from .multibody.imex import IMEX, JacobianCounter, check_jacobian_every
from .track import to_track_coordinates, track_frame
from .track.irregularity import rail_offsets
from .track.rails import HALF_TAPING_DISTANCE, track_irregularity
from .vehicles.drive import check_drive
from .vehicles.initial import initial_state
from .vehicles.loads import VehicleLoads, contact_loads, resolve_contact_model
from .vehicles.vehicle import Vehicle, VehicleParams, wheelset_states


def _f64(x):
    return jnp.asarray(x, dtype=jnp.float64)


class DerailmentLimits(eqx.Module):
    """A run stops as derailed when any wheelset's centre is more than ``lateral`` [m]
    from the track centreline or any wheel is ``lift`` [m] above its initial height
    (the S1002 flange is 28 mm high: at 25 mm lift the flange is on the rail head).
    Traced: changing them does not recompile."""

    lateral: jax.Array = eqx.field(converter=_f64, default=0.035)
    lift: jax.Array = eqx.field(converter=_f64, default=0.025)


INTEGRATORS = ("tsit5", "imex")


@dataclasses.dataclass(frozen=True)
class SolverOptions:
    """Integration settings (static: changing them recompiles).

    rtol, atol: PID controller tolerances; dt0 [s]: first step; max_steps: per run;
    n_outputs: number of equally spaced output times (including t = 0 and t1);
    (defaults measured in docs/simulation.md: rtol 1e-4 moves the wheelsets' lateral
    displacement by under 10 um against 1e-5 in 0.5 s, in two thirds of the steps)
    progress: show a progress bar of simulated seconds with the real-time factor.
    pcoeff, icoeff: the PID controller's proportional and integral coefficients
    (0.4 and 0.3: in flange contact the steps are limited by stability, where diffrax's
    plain integral controller (0 and 1) rejects one step in five; see docs/simulation.md).
    fixed_step: a constant step [s] instead of the controller (then rtol, atol, dt0,
    pcoeff and icoeff are unused): the outputs are then smooth functions of the
    parameters, which gradients checked by finite differences and fits need
    (docs/identification.md).
    integrator: one of :data:`INTEGRATORS`: "tsit5" (explicit, held to
    steps of about 0.3 ms by the stiff creep) or "imex" (the creep and the normal
    contact stiffness implicit, :class:`jaxrail.multibody.imex.IMEX`, KenCarp5;
    steps of about 1 ms; docs/simulation.md).
    jacobian_every: with "imex", a new load Jacobian every this many accepted steps,
    carried by the wheelsets' spin in between (1: every step; docs/simulation.md).
    """

    rtol: float = 1e-4
    atol: float = 1e-7
    dt0: float = 1e-4
    max_steps: int = 2_000_000
    n_outputs: int = 201
    progress: bool = False
    pcoeff: float = 0.4
    icoeff: float = 0.3
    fixed_step: float | None = None
    integrator: str = "tsit5"
    jacobian_every: int = 8

    def __post_init__(self):
        if self.fixed_step is not None and not self.fixed_step > 0.0:
            raise ValueError(f"fixed_step must be > 0 [s], got {self.fixed_step}")
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got "
                             f"{self.integrator!r}")
        check_jacobian_every(self.jacobian_every)

    def solver(self):
        """The diffrax solver of ``integrator``."""
        if self.integrator == "imex":
            return IMEX(jacobian_every=self.jacobian_every)
        return diffrax.Tsit5()

    def controller(self):
        """diffrax step-size controller and first step [s]."""
        if self.fixed_step is not None:
            return diffrax.ConstantStepSize(), self.fixed_step
        return diffrax.PIDController(rtol=self.rtol, atol=self.atol, pcoeff=self.pcoeff,
                                     icoeff=self.icoeff), self.dt0


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


class WheelOutputs(eqx.Module):
    """Contact details at the output times; leading shape (T, W, 2, P): time, wheelset
    (leading first), wheel (left, right), patch slot.

    Fields: active; surface (index into the wheel's surfaces); y_wheel, y_rail [m]
    lateral position of the contact point on the wheel and rail profiles; penetration
    [m]; contact_angle [rad]; normal_force [N]; creep_force_x, creep_force_y [N]
    (contact frame, on the wheel); creepage_x, creepage_y [-], spin [1/m].
    Per wheel (T, W, 2): lateral_force and vertical_force Q [N], track frame, on the
    wheel from the rail (lateral positive towards the wheel's own field side, so a
    flanging wheel has a negative value; Nadal's Y, the wheel's force on the rail, is
    its negative: :func:`jaxrail.results.derailment_ratio`).
    """

    active: jax.Array
    surface: jax.Array
    y_wheel: jax.Array
    y_rail: jax.Array
    penetration: jax.Array
    contact_angle: jax.Array
    normal_force: jax.Array
    creep_force_x: jax.Array
    creep_force_y: jax.Array
    creepage_x: jax.Array
    creepage_y: jax.Array
    spin: jax.Array
    lateral_force: jax.Array
    vertical_force: jax.Array


class SimulationResult(eqx.Module):
    """Output of :func:`simulate`.

    Fields:
        t (T,) [s]; q, qdot (T, 7 n): body states (jaxrail.multibody conventions);
        qddot (T, 7 n): their accelerations (eq. 19 with the loads of the outputs; NaN
            after an early stop);
        valid (T,): output times the run reached (False after an early stop);
        wheelset_lateral, wheelset_vertical, wheelset_yaw (T, W): wheelset centre
            relative to the design track centreline [m] and yaw relative to the track
            [rad];
        irregularity (T, W, 4): the track's irregularity channels at each wheelset
            (alignment, vertical level, cross level, gauge; :mod:`jaxrail.track.irregularity`)
            [m], zeros on an ideal track;
        rail_deflection (T, W, 2, 2): on a flexible track, the deflection of the rails
            under each wheelset (left, right; lateral along the canted track frame's
            ``n``, vertical along its ``b``) [m] (:mod:`jaxrail.track.flexible`),
            zeros on rigid rails;
        wheels: :class:`WheelOutputs`;
        constraint_violation (T,): max |Phi| over the joint rows;
        result: diffrax's result code; derailed: the derailment event fired;
        steps, accepted_steps, rejected_steps: integrator statistics;
        rhs_evaluations, jacobian_evaluations: the right-hand sides and load
            Jacobians the integration evaluated (:func:`evaluations_per_step`; -1 for a
            solver it does not know);
        wall_time_s, compile_time_s: host timings (NaN inside jit/vmap).
    """

    t: jax.Array
    q: jax.Array
    qdot: jax.Array
    qddot: jax.Array
    valid: jax.Array
    wheelset_lateral: jax.Array
    wheelset_vertical: jax.Array
    wheelset_yaw: jax.Array
    irregularity: jax.Array
    rail_deflection: jax.Array
    wheels: WheelOutputs
    constraint_violation: jax.Array
    result: jax.Array
    derailed: jax.Array
    steps: jax.Array
    accepted_steps: jax.Array
    rejected_steps: jax.Array
    rhs_evaluations: jax.Array
    jacobian_evaluations: jax.Array
    wall_time_s: jax.Array
    compile_time_s: jax.Array

    @property
    def status(self) -> str:
        """"successful", "derailed", "max_steps_reached", "failed: singular implicit
        solve" (the IMEX step's matrix was not finite or singular) or "failed" (a state
        that turned non-finite, or another diffrax failure) (host only, for an unbatched
        result)."""
        if bool(self.derailed):
            return "derailed"
        if self.result == diffrax.RESULTS.successful:
            return "successful"
        if self.result == diffrax.RESULTS.max_steps_reached:
            return "max_steps_reached"
        if self.result == diffrax.RESULTS.singular:
            return "failed: singular implicit solve"
        return "failed"

    @property
    def simulated_time_s(self) -> float:
        """Last output time the run reached [s]."""
        return float(np.max(np.where(np.asarray(self.valid), np.asarray(self.t), 0.0)))


def _wheelset_track_coordinates(vehicle, track, q, qdot):
    """Per wheelset: lateral [m], vertical [m] offsets and yaw [rad] relative to the
    design track, the height [m] of each wheel's taping point (W, 2) over its rail's
    place (the design track plane moved by the rail's vertical irregularity), and the
    irregularity channels at the wheelset (W, 4) [m] (:mod:`jaxrail.track.rails`)."""
    position, rotation, _, _ = wheelset_states(vehicle, q, qdot)
    sides = jnp.array([1.0, -1.0])

    def one(r, a):
        s, lateral, vertical = to_track_coordinates(track, r)
        frame = track_frame(track, s)
        axle = frame.T @ a[:, 1]
        yaw = -jnp.arctan2(axle[0], axle[1])
        irregularity = track_irregularity(track, s)
        rail_heights = rail_offsets(irregularity, sides)[1]
        wheel_heights = vertical + sides * HALF_TAPING_DISTANCE * axle[2] - rail_heights
        return lateral, vertical, yaw, wheel_heights, irregularity
    return jax.vmap(one)(position, rotation)


def _stop_events(vehicle, track, limits, rest_height):
    """The terminating diffrax Event of a run: (derailed, non-finite state)."""
    def derailed(t, y, args, **kwargs):
        q, qdot = y.q, y.qdot
        lateral, _, _, heights, irregularity = _wheelset_track_coordinates(vehicle, track, q,
                                                                           qdot)
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


def _outputs(vehicle, params, track, q, qdot, rails, model, t=0.0, drive=None, elements=None):
    """``(WheelOutputs, qddot)`` at one state: the wheel outputs (leading shape (W, 2,
    P)) and the accelerations (7 n,) of eq. (19) with the same loads, from one contact
    evaluation; ``rails``: the flexible track's ``(w, wdot)`` (W, 2, 2), or None;
    ``drive``: the run's speed drive (its force at time ``t`` [s]), or None;
    ``elements``: the force elements' internal states (:class:`State`)."""
    forces_on_bodies, torques, patches, forces = contact_loads(vehicle, params, track, q,
                                                               qdot, model, rails)
    if drive is not None:
        forces_on_bodies = drive.add_to(t, qdot, forces_on_bodies)
    qddot = accelerations(vehicle.system, params.system, 0.0, q, qdot,
                          FixedLoads(forces_on_bodies, torques), elements)[0]
    position, _, _, _ = wheelset_states(vehicle, q, qdot)
    frames = jax.vmap(lambda r: track_frame(track, to_track_coordinates(track, r)[0]))(position)
    side = jnp.array([1.0, -1.0])[None, :]
    total = jnp.sum(forces.force, axis=2)  # (W, 2, 3)
    lateral = jnp.einsum("wsi,wi->ws", total, frames[:, :, 1]) * side
    vertical = jnp.einsum("wsi,wi->ws", total, frames[:, :, 2])
    wheels = WheelOutputs(patches.active, patches.surface, patches.y_wheel, patches.y_rail,
                          patches.penetration, patches.contact_angle, forces.normal_force,
                          forces.creep_force_x, forces.creep_force_y, forces.creepage_x,
                          forces.creepage_y, forces.spin, lateral, vertical)
    return wheels, qddot


def _wheel_outputs(vehicle, params, track, q, qdot, rails, model):
    """WheelOutputs at one state (:func:`_outputs` without the accelerations)."""
    return _outputs(vehicle, params, track, q, qdot, rails, model)[0]


def _integrate(loads, start, rest_heights, t1, ts, options, limits, solver, adjoint,
               report=False):
    """diffrax's Solution of eq. (19) under ``loads`` (:class:`VehicleLoads`: the
    vehicle, its parameters, the track) from the :class:`State` ``start`` at 0 to t1
    [s] with ``solver``, saved at ``ts``, stopped by the derailment event (a flexible
    track's rails and the elements' internal states are integrated with the bodies);
    ``report``: each accepted step's time to the host (:class:`TimeReportingMeter`).
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
        event=_stop_events(loads.vehicle, loads.track, limits, rest_heights),
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


def _results(vehicle, params, track, model, start, ts, saved, result, derailed, steps,
             accepted_steps, rejected_steps, evaluations, drive=None):
    """SimulationResult from the :class:`State` ``saved`` at the output times (leading
    axis T; non-finite rows: not reached) and the ``start``, without host timings.
    ``drive``: the run's speed drive, or None."""
    q0, qdot0, rails0 = start.q, start.qdot, start.track
    q, qdot, rails = saved.q, saved.qdot, saved.track
    _, rest_vertical, _, _, _ = _wheelset_track_coordinates(vehicle, track, q0, qdot0)
    valid = jnp.all(jnp.isfinite(q), axis=1) & jnp.all(jnp.isfinite(qdot), axis=1)
    # Outputs after an early stop are recomputed at the initial state and masked.
    safe = lambda x, x0: jnp.where(valid.reshape((-1,) + (1,) * (x.ndim - 1)), x, x0)  # noqa: E731
    q_safe, qdot_safe = safe(q, q0), safe(qdot, qdot0)
    rails_safe = None if rails is None else jax.tree.map(safe, rails, rails0)
    elements_safe = jax.tree.map(safe, saved.elements, start.elements)
    lateral, vertical, yaw, _, irregularity = jax.vmap(
        lambda a, b: _wheelset_track_coordinates(vehicle, track, a, b))(q_safe, qdot_safe)
    wheels, qddot = jax.lax.map(
        lambda y: _outputs(vehicle, params, track, *y[1:4], model, y[0], drive, y[4]),
        (ts, q_safe, qdot_safe, rails_safe, elements_safe))
    deflection = (jnp.zeros(lateral.shape + (2, 2), dtype=q.dtype) if rails is None
                  else rails_safe[0])
    n_norm = vehicle.system.n_bodies
    violation = jax.vmap(lambda a, b: jnp.max(jnp.abs(
        constraints(vehicle.system, params.system, a, b)[0][n_norm:]), initial=0.0))(
        q_safe, qdot_safe)
    nan = lambda x: jnp.where(valid.reshape((-1,) + (1,) * (x.ndim - 1)), x, jnp.nan)  # noqa: E731
    wheels = jax.tree.map(lambda x: nan(x) if jnp.issubdtype(x.dtype, jnp.floating) else x,
                          wheels)
    return SimulationResult(
        t=ts, q=q, qdot=qdot, qddot=nan(qddot), valid=valid, wheelset_lateral=nan(lateral),
        wheelset_vertical=nan(vertical - rest_vertical), wheelset_yaw=nan(yaw),
        irregularity=nan(irregularity), rail_deflection=nan(deflection), wheels=wheels,
        constraint_violation=nan(violation),
        result=result, derailed=jnp.asarray(derailed), steps=steps, accepted_steps=accepted_steps,
        rejected_steps=rejected_steps, rhs_evaluations=evaluations[0],
        jacobian_evaluations=evaluations[1], wall_time_s=jnp.asarray(jnp.nan),
        compile_time_s=jnp.asarray(jnp.nan))


def _start(vehicle, params, track, speed, misalignment, s0, initial, model):
    """The :class:`State` a run starts from: ``initial``, or the static equilibrium."""
    if initial is None:
        initial = initial_state(vehicle, params, track, speed, misalignment, s0, model)
    return _as_state(vehicle, params, track, initial)


def _as_state(vehicle, params, track, initial) -> State:
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
    """The traceable core of :func:`simulate` (jit, vmap and grad it): returns a
    :class:`SimulationResult` without host timings. ``t1`` [s], ``speed`` [m/s] and
    ``misalignment`` [m] may be traced. ``initial``: a :class:`~jaxrail.multibody.State`
    (or on rigid rails ``(q0, qdot0)``) to start from instead of the static equilibrium
    (:func:`jaxrail.vehicles.initial_state`); wheel lifts and vertical displacements
    are measured from the initial state. ``contact_model``: :mod:`jaxrail.vehicles.loads`
    (default the paper's search). ``options.progress`` is not used here
    (:func:`simulate` draws the bar). ``limits``: :class:`DerailmentLimits` (default
    ones). ``report_progress``: pass each step's time to the host
    (:mod:`jaxrail._time_report`; it changes no value), as :func:`simulate` does for
    its progress bar. ``drive``: a :class:`~jaxrail.vehicles.drive.SpeedDrive` holding
    the speed to its programme (default None: the vehicle coasts)."""
    limits = DerailmentLimits() if limits is None else limits
    loads = VehicleLoads(vehicle, params, track, resolve_contact_model(contact_model), drive)
    start = _start(vehicle, params, track, speed, misalignment, s0, initial, loads.model)
    lateral0, _, _, rest_heights, irregularity0 = _wheelset_track_coordinates(
        vehicle, track, start.q, start.qdot)
    ts = jnp.linspace(0.0, t1, options.n_outputs)
    solver = options.solver() if solver is None else solver
    sol = _integrate(loads, start, rest_heights, t1, ts, options, limits, solver, adjoint,
                     report_progress)
    # a state that only turned non-finite is not derailed: diffrax's event_occurred
    # result makes the status "failed"
    derailed = sol.event_mask[0] | _starts_derailed(limits, lateral0, irregularity0,
                                                    misalignment)
    return _results(vehicle, params, track, loads.model, start, ts,
                    _saved_states(sol, start), sol.result, derailed,
                    sol.stats["num_steps"], sol.stats["num_accepted_steps"],
                    sol.stats["num_rejected_steps"],
                    _evaluations(solver, sol), drive)


PROGRAMS_KEPT = 32
"""Compiled programs this process keeps (:func:`_compile`); the least recently used
one goes first (a paper-curve run uses two: rest pose and run)."""
_compiled = LruCache(PROGRAMS_KEPT)


def _compile(function, *args, **kwargs):
    """AOT-compile ``function`` (jitted, or a plain function: see
    :func:`jaxrail._compiler.compile_function`) for these arguments once per static
    structure and argument shapes; returns (compiled, compile time [s], 0 if it was
    already compiled in this process)."""
    leaves, structure = jax.tree.flatten((args, kwargs))
    key = (function, structure, tuple((x.shape, x.dtype) if eqx.is_array(x) else x
                                      for x in leaves))
    start = time.perf_counter()
    compiled, made = _compiled.get_or_make(
        key, lambda: compile_function(function, *args, **kwargs))
    return compiled, (time.perf_counter() - start if made else 0.0)


class _Timer:
    """Compiles through :func:`_compile` and adds up the compile seconds."""

    def __init__(self):
        self.compile_s = 0.0

    def compile(self, function, *args, **kwargs):
        compiled, seconds = _compile(function, *args, **kwargs)
        self.compile_s += seconds
        return compiled

    def run(self, function, *args, **kwargs):
        return self.compile(function, *args, **kwargs)(*args, **kwargs)


def run_span(params: VehicleParams, speed, t1, s0=None) -> tuple[float, float]:
    """Arc lengths [m] the wheelsets' positions cover in a run of ``t1`` [s] at ``speed``
    [m/s] from ``s0`` (:func:`jaxrail.vehicles.initial_state`'s default: the rearmost
    body 5 m after the start): ``(first, last)``, from the rearmost wheelset's start to
    the leading one's end (host values)."""
    x = np.asarray(params.layout)[:, 0]
    s0 = 5.0 - float(np.min(x)) if s0 is None else float(s0)
    return s0 + float(np.min(x)), s0 + float(np.max(x)) + float(speed) * float(t1)


def warn_beyond_track(track, span) -> None:
    """Warn when ``span`` (first, last) [m] of a run goes past the ends of the design
    track, naming how far: the end segments continue by their own law there
    (docs/track.md)."""
    length = float(track.total_length)
    first, last = span
    if last > length:
        warnings.warn(f"the run reaches s = {last:.1f} m, {last - length:.1f} m past the end of "
                      f"the {length:g} m design track: its last segment continues by its own "
                      "law (a straight stays straight, an arc the same circle)", stacklevel=3)
    if first < 0.0:
        warnings.warn(f"the run starts at s = {first:.1f} m, {-first:.1f} m before the design "
                      "track: its first segment continues by its own law", stacklevel=3)


def simulate(vehicle: Vehicle, params: VehicleParams, track, t1: float, speed: float,
             misalignment: float = 0.0, s0=None, options: SolverOptions = SolverOptions(),
             limits: DerailmentLimits | None = None, initial=None,
             solver=None, contact_model=None, drive=None) -> SimulationResult:
    """Run a vehicle along a track for ``t1`` [s] at ``speed`` [m/s] from static
    equilibrium, shifted ``misalignment`` [m] to the left (or from ``initial`` =
    ``(q0, qdot0)``); see the module docstring. ``solver``: a diffrax solver (default
    ``options.solver()``). ``contact_model``: :mod:`jaxrail.vehicles.loads` (default the paper's
    search, :class:`~jaxrail.vehicles.OnlineContact`). ``drive``: a
    :class:`~jaxrail.vehicles.drive.SpeedDrive` that holds the speed to a programme
    (default None: the vehicle coasts from ``speed``).

    The compiled programs (initial equilibrium, integration, outputs) are cached: a
    second call with the same vehicle structure and options does not recompile,
    whatever the numbers; none holds a host callback, so JAX's persistent compilation
    cache can keep them across processes (:mod:`jaxrail._compiler`). The run is one
    program whether or not ``options.progress`` draws a bar: its loop reports each
    accepted step's time to the host through diffrax's progress-meter hook and an XLA
    FFI target (:mod:`jaxrail._time_report`),
    which the bar reads, so a run with the bar takes the same steps and gives the same
    result, bit for bit, as one without. Returns a :class:`SimulationResult` with wall
    and compile times [s].
    """
    start = time.perf_counter()
    if drive is not None:
        check_drive(drive, vehicle.system.n_bodies)
    if initial is None:
        warn_beyond_track(track, run_span(params, speed, t1, s0))
    limits = DerailmentLimits() if limits is None else limits
    # the default model spelt out, so that None and OnlineContact() share one program
    contact_model = resolve_contact_model(contact_model)
    t1, speed, misalignment = (jnp.float64(x) for x in (t1, speed, misalignment))
    s0 = None if s0 is None else jnp.float64(s0)
    timer = _Timer()
    if initial is None:
        initial = timer.run(initial_state, vehicle, params, track, speed, misalignment, s0,
                            contact_model)
    initial = _as_state(vehicle, params, track, initial)
    # progress only draws: one program (and one cache entry) with or without the bar
    arguments = (vehicle, params, track, t1, speed, misalignment, s0)
    static = dict(options=dataclasses.replace(options, progress=False), limits=limits,
                  initial=initial, solver=solver, contact_model=contact_model,
                  report_progress=True, drive=drive)
    run = timer.compile(solve, *arguments, **static)
    if options.progress:
        with SimulatedTimeBar(float(t1)) as bar, listening(bar.update):
            result = jax.block_until_ready(run(*arguments, **static))
            bar.update(result.simulated_time_s)
    else:
        result = run(*arguments, **static)
    jax.block_until_ready(result)
    wall = time.perf_counter() - start - timer.compile_s
    return eqx.tree_at(lambda r: (r.wall_time_s, r.compile_time_s), result,
                       (jnp.asarray(wall), jnp.asarray(timer.compile_s)))
