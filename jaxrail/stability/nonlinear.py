"""Nonlinear critical speed: the two standard methods, by simulation on straight track.

Both drive the vehicle's heaviest body at a programmed speed
(:class:`~jaxrail.vehicles.drive.SpeedDrive`) and watch one wheelset's lateral
displacement y(t) [m] (from the track centreline). Its amplitude at time t is half the
peak-to-peak of y over the ``window`` [s] centred on t (:func:`envelope`).

- **Ramp-down** (:func:`ramp_down`): the wheelset is shifted ``disturbance`` [m] at
  rest and run at ``start_speed`` for ``hold`` [s], where it settles on a hunting limit
  cycle (the attractor, reported with its amplitude and frequency); then the speed
  falls at ``rate`` [m/s^2] (GENSYS's example: 5 km/h per second). The critical speed
  is the programmed speed when the amplitude last fell below ``threshold`` [m]: the
  oscillation has died. The centred window sees a peak up to half a window after it,
  so this reads up to ``rate * window / 2`` low (0.35 m/s at 5 km/h per second).
- **Brute force** (:func:`brute_force`): constant-speed runs of ``duration`` [s],
  several speeds at once (one ``vmap``ped program), classified as hunting when the
  amplitude over the last ``window`` is at least ``threshold`` (or the wheelset
  derailed). A batch tests the bracket's lower end and speeds inside it; the slowest
  of the hunting runs above every dying one and the dying run below it make the next
  bracket, until it is narrower than ``resolution`` [m/s]. The first batch starts on
  the limit cycle found at the top speed (``hold`` [s] there after the
  ``disturbance``; :func:`limit_cycle`), each later one from the final state of the
  bracket's hunting run, each state moved to the run's speed
  (:func:`state_at_speed`). With ``start="shift"`` every run starts from the rest pose
  shifted by ``disturbance`` instead.

Below the linear critical speed a hunting wheelset's large limit cycle and centred
running are both stable (a subcritical bifurcation): which one a run ends on depends on
its start, and near the lowest speed at which the large cycle lives its basin is thin.
Starting each batch on the cycle of a speed ever closer to the ones it tests keeps the
starts inside it (from the 95 m/s cycle itself, the suspended wheelset's runs died up
to 76.6 m/s, where the ramp-down followed the cycle down to 72.5 m/s).

A run's speed and the wheelset's motion are saved at ``OUTPUT_RATE`` per second.
"""

import dataclasses
import math
import time
import warnings

import diffrax
import jax
import jax.numpy as jnp
import numpy as np

from ..compilation import compile_program
from ..multibody import quaternion as qt
from ..simulation import SolverOptions, simulate, solve
from ..vehicles.drive import SpeedDrive, check_drive
from .linear import check_straight

GENSYS_RATE = 5.0 / 3.6
"""[m/s^2] the ramp-down rate of GENSYS's example, 5 km/h per second."""
THRESHOLD = 1.0e-3  # [m] amplitude below which the oscillation has died [A]
WINDOW = 0.5  # [s] amplitude window: at least two periods of hunting above 4 Hz [A]
DISTURBANCE = 5.0e-3  # [m] lateral shift of the rest pose that starts the motion [A]
OUTPUT_RATE = 400.0  # [1/s] outputs: 50 per period of 8 Hz hunting


def driven_body(vehicle) -> int:
    """The body the speed drive acts on: the ``carbody``, else the ``frame``
    (ValueError if the vehicle has neither)."""
    for name in ("carbody", "frame"):
        if name in vehicle.system.body_names:
            return vehicle.system.body_names.index(name)
    raise ValueError(f"the nonlinear stability methods drive a body named 'carbody' or "
                     f"'frame'; {vehicle.name!r} has {vehicle.system.body_names}")


def vehicle_mass(params) -> jax.Array:
    """The vehicle's whole mass [kg]."""
    return jnp.sum(params.system.bodies.mass)


def envelope(t, y, window=WINDOW) -> np.ndarray:
    """Half the peak-to-peak of ``y`` over the ``window`` [s] centred on each sample of
    the equally spaced times ``t`` (cut short at the ends); NaN samples are ignored."""
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    half = max(1, int(round(0.5 * window / (t[1] - t[0]))))
    padded = np.concatenate([np.full(half, np.nan), y, np.full(half, np.nan)])
    views = np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1)
    with warnings.catch_warnings():  # all-NaN windows after a run's early end
        warnings.simplefilter("ignore", RuntimeWarning)
        return 0.5 * (np.nanmax(views, axis=1) - np.nanmin(views, axis=1))


def oscillation_frequency(t, y) -> float:
    """Frequency [Hz] of ``y`` from its upward crossings of its mean (NaN with fewer
    than two)."""
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    keep = np.isfinite(y)
    t, y = t[keep], y[keep]
    if len(y) < 3:
        return math.nan
    y = y - np.mean(y)
    up = np.nonzero((y[:-1] < 0.0) & (y[1:] >= 0.0))[0]
    if len(up) < 2:
        return math.nan
    crossing = t[up] - y[up] * (t[up + 1] - t[up]) / (y[up + 1] - y[up])
    return (len(crossing) - 1) / (crossing[-1] - crossing[0])


def attractor(t, y, window=WINDOW, threshold=THRESHOLD) -> dict:
    """The motion over the last ``window`` [s] of ``y`` [m]: amplitude [m], frequency [Hz]
    (None at rest) and whether it is a hunting limit cycle (amplitude at least
    ``threshold``) or rest."""
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    last = t >= t[-1] - window
    amplitude = 0.5 * float(np.nanmax(y[last]) - np.nanmin(y[last]))
    hunting = bool(amplitude >= threshold)
    return {"kind": "hunting limit cycle" if hunting else "rest (centred running)",
            "amplitude_m": amplitude, "mean_m": float(np.nanmean(y[last])),
            "frequency_hz": oscillation_frequency(t[last], y[last]) if hunting else None}


def check_straight_x(track) -> None:
    """ValueError unless ``track`` is ideal, rigid and straight along global x (the
    drive pushes along x)."""
    check_straight(track)
    heading = float(np.asarray(track.heading_start)[0])
    if abs(heading) > 1e-12:
        raise ValueError(f"the nonlinear stability methods need a straight track along "
                         f"global x (heading 0), got heading {heading:g} rad")


def _options(options, duration):
    if options is None:
        options = SolverOptions(integrator="imex")
    n = int(math.ceil(duration * OUTPUT_RATE)) + 1
    return dataclasses.replace(options, n_outputs=n, progress=False)


def _check_speeds(low, high, what):
    if not (math.isfinite(low) and math.isfinite(high) and 0.0 < low < high):
        raise ValueError(f"{what}: need 0 < low < high [m/s], got {low}, {high}")


def ramp_down(vehicle, params, track, start_speed, end_speed, rate=GENSYS_RATE, hold=2.0,
              disturbance=DISTURBANCE, wheelset=0, threshold=THRESHOLD, window=WINDOW,
              options=None, contact_model=None) -> dict:
    """The ramp-down method (module docstring) from ``start_speed`` down to
    ``end_speed`` [m/s] at ``rate`` [m/s^2] after ``hold`` [s]. Returns a JSON-ready
    dict: ``critical_speed_m_s`` (None if the oscillation lasted to ``end_speed`` or
    there was none to start with: ``status`` says which), the attractor at the end of
    the hold, and the amplitude against the programmed speed (every 0.05 s)."""
    _check_speeds(end_speed, start_speed, "ramp-down")
    check_straight_x(track)
    if not (rate > 0.0 and hold > 0.0 and window > 0.0 and threshold > 0.0):
        raise ValueError(f"ramp-down: rate, hold, window and threshold must be > 0, got "
                         f"{rate}, {hold}, {window}, {threshold}")
    duration = hold + (start_speed - end_speed) / rate
    drive = SpeedDrive(driven_body(vehicle), start_speed, vehicle_mass(params), rate, hold)
    check_drive(drive, vehicle.system.n_bodies)
    started = time.perf_counter()
    result = simulate(vehicle, params, track, duration, start_speed, disturbance,
                      options=_options(options, duration), contact_model=contact_model,
                      drive=drive)
    t = np.asarray(result.t)
    y = np.asarray(result.wheelset_lateral)[:, wheelset]
    amplitude = envelope(t, y, window)
    reference = np.asarray(drive.reference_speed(jnp.asarray(t)))
    held = t <= hold
    limit_cycle = attractor(t[held], y[held], window, threshold)
    ramp = ~held & np.isfinite(amplitude)
    alive = ramp & (amplitude >= threshold)
    if result.status != "successful":
        status = (f"the run ended {result.status} at "
                  f"{float(result.simulated_time_s):.2f} s")
        critical = None
    elif limit_cycle["kind"] != "hunting limit cycle":
        status, critical = "no hunting at the start speed: start faster or disturb more", None
    elif alive[ramp][-1]:
        status, critical = "still hunting at the end speed: end slower", None
    else:
        last = np.nonzero(alive)[0]
        critical = float(reference[last[-1]]) if len(last) else float(start_speed)
        status = "found"
    step = max(1, int(round(0.05 * OUTPUT_RATE)))
    return {
        "method": "ramp-down",
        "status": status,
        "critical_speed_m_s": critical,
        "critical_speed_km_h": None if critical is None else 3.6 * critical,
        "start_speed_m_s": float(start_speed), "end_speed_m_s": float(end_speed),
        "rate_m_s2": float(rate), "rate_km_h_per_s": 3.6 * float(rate), "hold_s": float(hold),
        "excitation": f"rest pose shifted {1e3 * disturbance:g} mm to the left, then "
                      f"{hold:g} s at {start_speed:g} m/s",
        "attractor_at_start_speed": limit_cycle,
        "threshold_m": float(threshold), "window_s": float(window), "wheelset": int(wheelset),
        "speed_error_max_m_s": float(np.nanmax(np.abs(
            np.asarray(result.qdot)[:, 7 * drive.body] - reference))),
        "run_time_s": time.perf_counter() - started,
        "compile_time_s": float(result.compile_time_s),
        "amplitude_against_speed": [
            {"t_s": float(a), "speed_m_s": float(b), "amplitude_m": float(c)}
            for a, b, c in zip(t[::step], reference[::step], amplitude[::step])],
    }


def state_at_speed(vehicle, params, q, qdot, speed, new_speed):
    """The state ``(q, qdot)`` of a vehicle running at ``speed`` [m/s] along global x,
    moved to ``new_speed``: every body's velocity along x changed by the difference,
    every wheelset's spin about its axle by the difference over the nominal radius (so
    the creepages stay as they were); the positions as they are."""
    change = new_speed - speed
    rates = qdot.reshape(-1, 7).at[:, 0].add(change)
    for k in vehicle.wheelsets:
        p = q.reshape(-1, 7)[k, 3:]
        axle = qt.rotation_matrix(p)[:, 1]
        spin = change / params.wheel.nominal_radius * axle
        rates = rates.at[k, 3:].add(qt.pdot_from_omega_global(p, spin))
    return q, rates.reshape(-1)


def limit_cycle(vehicle, params, track, speed, hold=2.0, disturbance=DISTURBANCE,
                wheelset=0, threshold=THRESHOLD, window=WINDOW, options=None,
                contact_model=None):
    """The motion at ``speed`` [m/s], held there by the drive, ``hold`` [s] after the
    rest pose shifted ``disturbance`` [m]: ``(q, qdot, attractor)``, the final state and
    :func:`attractor` of the wheelset's lateral motion over the last ``window``."""
    drive = SpeedDrive(driven_body(vehicle), speed, vehicle_mass(params))
    result = simulate(vehicle, params, track, hold, speed, disturbance,
                      options=_options(options, hold), contact_model=contact_model,
                      drive=drive)
    if result.status != "successful":
        raise ValueError(f"the run at {speed:g} m/s that excites the limit cycle ended "
                         f"{result.status} at {float(result.simulated_time_s):.2f} s")
    y = np.asarray(result.wheelset_lateral)[:, wheelset]
    return result.q[-1], result.qdot[-1], attractor(np.asarray(result.t), y, window, threshold)


def _constant_speed_runs(vehicle, params, track, speeds, duration, disturbance, mass, start,
                         *, body, options, contact_model):
    """:func:`jaxrail.simulation.solve` at each of ``speeds`` (B,) [m/s], driven at that
    constant speed, from the rest pose shifted ``disturbance`` [m] (``start`` None) or
    from ``start = (q, qdot, speed)`` moved to each speed (:func:`state_at_speed`): the
    wheelsets' lateral displacements (B, T, W) [m], the driven body's speed (B, T), the
    derailed flags (B,), whether diffrax ended successfully (B,) and the final states
    ``(q, qdot)`` (B, 7 n) (non-finite after an early stop)."""
    def one(speed):
        drive = SpeedDrive(body, speed, mass)
        initial = None if start is None else state_at_speed(vehicle, params, start[0],
                                                            start[1], start[2], speed)
        result = solve(vehicle, params, track, duration, speed, disturbance, options=options,
                       contact_model=contact_model, drive=drive, initial=initial)
        return (result.wheelset_lateral, result.qdot[:, 7 * body], result.derailed,
                result.result == diffrax.RESULTS.successful, result.q[-1], result.qdot[-1])
    return jax.vmap(one)(speeds)


STARTS = ("limit cycle", "shift")


def brute_force(vehicle, params, track, low, high, resolution=0.5, duration=5.0,
                disturbance=DISTURBANCE, start="limit cycle", hold=2.0, runs_per_batch=4,
                wheelset=0, threshold=THRESHOLD, window=WINDOW, options=None,
                contact_model=None, progress=None, max_batches=12) -> dict:
    """The brute-force method (module docstring) over ``[low, high]`` [m/s]: batches
    of ``runs_per_batch`` constant-speed runs of ``duration`` [s] until the bracket
    between a dying speed and the slowest hunting one above it is narrower than
    ``resolution`` [m/s], at most ``max_batches``; ``start`` one of :data:`STARTS`.
    ``progress``: a callable given a line per batch, or None. Returns a JSON-ready dict: ``critical_speed_m_s``
    (the bracket's middle; None if ``low`` already hunts or ``high`` does not:
    ``status`` says which), the bracket, the excitation, every run with its
    attractor."""
    _check_speeds(low, high, "brute force")
    check_straight_x(track)
    if not (resolution > 0.0 and duration > 2.0 * window and runs_per_batch >= 2):
        raise ValueError(f"brute force: need resolution > 0, duration > 2 windows and at "
                         f"least 2 runs per batch, got {resolution}, {duration}, "
                         f"{runs_per_batch}")
    if start not in STARTS:
        raise ValueError(f"brute force: start must be one of {STARTS}, got {start!r}")
    body = driven_body(vehicle)
    check_drive(SpeedDrive(body, high, vehicle_mass(params)), vehicle.system.n_bodies)
    started = time.perf_counter()
    shift = f"the rest pose shifted {1e3 * disturbance:g} mm to the left"
    if start == "shift":
        initial, excitation, cycle = None, f"{shift}, at each speed held constant", None
    else:
        q, qdot, cycle = limit_cycle(vehicle, params, track, high, hold, disturbance,
                                     wheelset, threshold, window, options, contact_model)
        if cycle["kind"] != "hunting limit cycle":
            raise ValueError(f"brute force: no limit cycle at {high:g} m/s {hold:g} s after "
                             f"{shift} (amplitude {1e3 * cycle['amplitude_m']:.3f} mm): "
                             "go higher or disturb more")
        initial = (q, qdot, jnp.float64(high))
        excitation = (f"the state {hold:g} s after {shift} at {high:g} m/s (on its limit "
                      "cycle), moved to each speed")
    options = _options(options, duration)
    static = dict(body=body, options=options, contact_model=contact_model)
    arrays = lambda speeds: (vehicle, params, track, jnp.asarray(speeds, jnp.float64),  # noqa: E731
                             jnp.float64(duration), jnp.float64(disturbance),
                             vehicle_mass(params), initial)
    t = np.linspace(0.0, duration, options.n_outputs)
    lo, hi, runs, compile_s, mixed, first = low, high, [], 0.0, False, True
    while True:
        # from the shifted rest pose the first batch tests ``high`` too; from a limit
        # cycle ``hi`` is known to hunt
        speeds = (np.linspace(lo, hi, runs_per_batch) if first and initial is None
                  else np.linspace(lo, hi, runs_per_batch + 1)[:-1])
        run, seconds = compile_program(_constant_speed_runs, *arrays(speeds), **static)
        compile_s += seconds
        lateral, speed, derailed, ended, q_end, qdot_end = jax.tree.map(
            np.asarray, run(*arrays(speeds), **static))
        batch = []
        for k, v in enumerate(speeds):
            y = lateral[k, :, wheelset]
            keep = np.isfinite(y)
            motion = attractor(t[keep], y[keep], window, threshold) if keep.sum() > 2 else {}
            batch.append({
                "speed_m_s": float(v),
                "hunting": bool(derailed[k]) or motion.get("kind") == "hunting limit cycle",
                "derailed": bool(derailed[k]),
                "failed": bool(not derailed[k] and (not ended[k] or not keep.all())),
                "started_from_m_s": None if initial is None else float(initial[2]),
                "attractor": motion,
                "speed_error_max_m_s": float(np.nanmax(np.abs(speed[k] - v)))})
        runs += batch
        if progress is not None:
            progress(" ".join(f"{r['speed_m_s']:.2f}:{'H' if r['hunting'] else '-'}"
                              for r in batch))
        if any(r["failed"] for r in batch):
            status = "a run failed: " + ", ".join(f"{r['speed_m_s']:.2f} m/s"
                                                  for r in batch if r["failed"])
            bracket = None
            break
        # the hunting runs contiguous from the top of the batch
        k = len(batch)
        while k > 0 and batch[k - 1]["hunting"]:
            k -= 1
        mixed |= any(r["hunting"] for r in batch[:k])
        if k == 0 and speeds[0] <= low:
            status, bracket = "hunting already at the lowest speed: start lower", None
            break
        if k == len(batch) and first and initial is None:
            status = "no hunting up to the highest speed: go higher or disturb more"
            bracket = None
            break
        first = False
        if k < len(batch):
            hi = float(speeds[k])
            if initial is not None and np.all(np.isfinite(q_end[k])):
                # the next batch starts on the limit cycle of the slowest hunting run
                initial = (jnp.asarray(q_end[k]), jnp.asarray(qdot_end[k]), jnp.float64(hi))
        # the bracket's lower end hunts from a start closer to it than the one it died
        # from: the dying speed below it is not known any more, back to ``low``
        lo = float(speeds[k - 1]) if k > 0 else float(low)
        bracket = (lo, hi)
        if hi - lo <= resolution:
            status = "found"
            break
        if len(runs) >= max_batches * runs_per_batch:
            status = f"not converged in {max_batches} batches: bracket {lo:.2f}-{hi:.2f} m/s"
            break
    critical = None if bracket is None else 0.5 * (bracket[0] + bracket[1])
    return {
        "method": "brute force",
        "status": status,
        "critical_speed_m_s": critical,
        "critical_speed_km_h": None if critical is None else 3.6 * critical,
        "bracket_m_s": None if bracket is None else list(bracket),
        "resolution_m_s": float(resolution), "duration_s": float(duration),
        "excitation": excitation,
        "limit_cycle_at_start": cycle,
        "hunting_below_a_dying_speed": bool(mixed),
        "threshold_m": float(threshold), "window_s": float(window), "wheelset": int(wheelset),
        "runs": runs,
        "wall_time_s": time.perf_counter() - started,
        "batch_compile_time_s": compile_s,
    }
