"""The run: :func:`simulate` on the host, around :func:`~jaxrail.simulation.solve`:
it checks the drive, warns when the run leaves the design track, compiles the rest pose
and the run once per structure (:func:`jaxrail.compilation.compile_program`), draws the
progress bar and times the compile and the run."""

import dataclasses
import time
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._progress import SimulatedTimeBar
from .._time_report import listening
from ..compilation import CompileTimer
from ..vehicles.drive import check_drive
from ..vehicles.initial import initial_state
from ..vehicles.loads import resolve_contact_model
from ..vehicles.vehicle import Vehicle, VehicleParams
from .integrate import as_state, solve
from .options import DerailmentLimits, SolverOptions
from .result import SimulationResult

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
    cache can keep them across processes (:mod:`jaxrail.compilation`). The run is one
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
    timer = CompileTimer()
    if initial is None:
        initial = timer.run(initial_state, vehicle, params, track, speed, misalignment, s0,
                            contact_model)
    initial = as_state(vehicle, params, track, initial)
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
