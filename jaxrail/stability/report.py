"""The stability study of a scenario's vehicle: the hunting mode over a speed range
(the root locus), the linear critical speed and the EN 15302 equivalent conicity, and
on request the nonlinear critical speed by both methods, as JSON-ready dicts and
terminal tables (what ``jaxrail stability`` prints)."""

import math

import numpy as np

from ..geometry import wheelset_geometry
from ..geometry.report import conicity_entries
from ..vehicles import contact_model
from ..simulation import SolverOptions
from ..track import Arc, Track, straight_track
from .critical import LinearStability
from .linear import check_straight
from .nonlinear import GENSYS_RATE, brute_force, ramp_down

CONICITY_AMPLITUDE_M = 3e-3  # [m] amplitude of the reported equivalent conicity
_SHIFTS = np.round(np.arange(-10.0, 10.0 + 1e-9, 0.1), 9) * 1e-3  # [m] for the conicity


def speed_range(text: str, option: str = "--speeds") -> tuple[float, float]:
    """``(low, high)`` [m/s] of ``LO:HI``; ValueError names ``option``."""
    parts = text.split(":")
    try:
        low, high = (float(p) for p in parts) if len(parts) == 2 else (math.nan, math.nan)
    except ValueError:
        low = high = math.nan
    if not (math.isfinite(low) and math.isfinite(high) and 0.0 < low < high):
        raise ValueError(f"{option} {text!r}: give LO:HI in m/s with 0 < LO < HI, e.g. 20:150")
    return low, high


def curve_option(text: str, option: str = "--curve") -> tuple[float, float]:
    """``(radius [m], cant [m])`` of ``RADIUS[:CANT]``; ValueError names ``option``."""
    parts = text.split(":")
    try:
        radius, cant = float(parts[0]), (float(parts[1]) if len(parts) == 2 else 0.0)
    except (ValueError, IndexError):
        radius = cant = math.nan
    if len(parts) > 2 or not (math.isfinite(radius) and radius > 0.0 and math.isfinite(cant)
                              and abs(cant) < 0.3):
        raise ValueError(f"{option} {text!r}: give RADIUS[:CANT] in m with RADIUS > 0 and "
                         f"|CANT| < 0.3, e.g. 3000:0.1")
    return radius, cant


def curve_track(radius, cant=0.0, rail_centre_distance=1.5, rails=None) -> Track:
    """A left curve of ``radius`` [m] and ``cant`` [m], 300 m of one arc from the origin
    heading along +x (the stability analysis in a curve), with ``rails`` (default the
    standard ones, :func:`jaxrail.track.standard_rails`)."""
    return Track.from_segments([Arc(300.0, radius, "left", cant)],
                               rail_centre_distance=rail_centre_distance, rails=rails)


SPEED_RANGE_FACTORS = (0.25, 3.0)
"""The root locus's default speed range: these factors on the scenario's speed."""


def default_speed_range(scenario) -> tuple[float, float]:
    """``(low, high)`` [m/s], the root locus's range when none is given: 0.25 to 3 times
    the scenario's speed (:data:`SPEED_RANGE_FACTORS`)."""
    low, high = SPEED_RANGE_FACTORS
    return low * scenario.speed, high * scenario.speed


def nonlinear_options(scenario) -> SolverOptions:
    """The solver of the scenario's nonlinear critical speed (``jaxrail stability
    --nonlinear``): IMEX with the scenario's tolerances and Jacobian reuse."""
    return SolverOptions(rtol=scenario.rtol, atol=scenario.atol, integrator="imex",
                         jacobian_every=scenario.jacobian_every)


def study_setup(scenario, curve=None, contact="online", progress=False):
    """``(vehicle, params, track, model)`` of the stability study of ``scenario``: its
    vehicle on ideal, rigid track (no irregularity, no flexible support), straight, or
    with ``curve`` = ``(radius [m], cant [m])`` a left curve (:func:`curve_track`,
    about the steady curving state); ``model``: the contact table of ``contact`` =
    "table" (from the cache, or built with a progress bar when ``progress``), None for
    the search at every evaluation ("online")."""
    vehicle, params, track = scenario.build(None if curve is None else curve[0])
    if curve is not None:
        track = curve_track(*curve, rail_centre_distance=track.rail_centre_distance,
                            rails=track.rails)
    model = (contact_model(contact, vehicle, params, track, progress=progress)
             if contact == "table" else None)
    return vehicle, params, track.with_irregularity(None).with_support(None), model


def equivalent_conicity(vehicle, params, track, amplitude=CONICITY_AMPLITUDE_M) -> float:
    """EN 15302 equivalent conicity [-] of the vehicle's wheel on the track's rails at
    their gauge, at ``amplitude`` [m] (integral method on the quasi-static rolling
    radius difference over +-10 mm)."""
    geometry = wheelset_geometry(params.wheel, track.rails, _SHIFTS)
    entries = conicity_entries(_SHIFTS, np.asarray(geometry.delta_r),
                               float(params.wheel.nominal_radius), (1e3 * amplitude,))
    return entries[0]["tan_gamma_e"]


def stability_study(vehicle, params, track, low, high, points=9, model=None) -> dict:
    """The hunting mode at ``points`` speeds over ``[low, high]`` [m/s], the linear
    critical speed there (:meth:`LinearStability.critical_speed`: ValueError if the
    range holds no crossing) and the equivalent conicity at 3 mm."""
    if not (math.isfinite(low) and math.isfinite(high) and 0.0 < low < high) or points < 2:
        raise ValueError(f"stability study: need 0 < low < high [m/s] and at least 2 "
                         f"points, got {low}, {high}, {points}")
    stability = LinearStability(vehicle, params, track, model)
    sweep = stability.sweep(np.linspace(low, high, points))
    critical = stability.critical_speed(low, high, points=sweep)
    row = lambda p: {"speed_m_s": p.speed, "real_part_1_s": p.eigenvalue.real,  # noqa: E731
                     "frequency_hz": p.frequency_hz, "damping_ratio": p.damping_ratio,
                     "hunting_share": p.hunting_share}
    where = "straight track"
    curving = {}
    if stability.curving is not None:
        radius = 1.0 / abs(float(track.curvature_start[0]))
        cant = float(track.superelevation_start[0])
        where = f"a curve of radius {radius:g} m and cant {cant:g} m"
        state = stability.curving(critical.speed)
        curving = {"track": {"kind": "curve", "radius_m": radius, "cant_m": cant},
                   "steady_curving_at_critical_speed": {
                       "wheelset_lateral_m": state.wheelset_lateral_m.tolist(),
                       "wheelset_yaw_rad": state.wheelset_yaw_rad.tolist(),
                       "tangential_force_n": state.tangential_force_n,
                       "newton_iterations": state.iterations}}
    return {
        "vehicle": vehicle.name,
        "contact": stability.model.name,
        "linear_critical_speed_m_s": critical.speed,
        "linear_critical_speed_km_h": 3.6 * critical.speed,
        "hunting_frequency_hz": critical.frequency_hz,
        "equivalent_conicity": equivalent_conicity(vehicle, params, track),
        "equivalent_conicity_amplitude_m": CONICITY_AMPLITUDE_M,
        "method": (f"eigenvalues of the forward-mode Jacobian about the steady motion on "
                   f"{where}; critical speed where the least damped hunting mode's "
                   f"real part crosses zero (Illinois root solve)"),
        "root_locus": [row(p) for p in sweep],
        **curving,
    }


def format_study(study: dict) -> str:
    """The study as a plain-text table for the terminal."""
    lines = [f"{'speed m/s':>10} {'km/h':>7} {'freq Hz':>8} {'damping':>9} {'share':>6}"]
    for r in study["root_locus"]:
        lines.append(f"{r['speed_m_s']:10.2f} {3.6 * r['speed_m_s']:7.1f} "
                     f"{r['frequency_hz']:8.3f} {r['damping_ratio']:9.4f} "
                     f"{r['hunting_share']:6.2f}")
    conicity = study["equivalent_conicity"]
    lines += [
        f"linear critical speed: {study['linear_critical_speed_m_s']:.2f} m/s "
        f"({study['linear_critical_speed_km_h']:.1f} km/h), hunting at "
        f"{study['hunting_frequency_hz']:.3f} Hz",
        f"equivalent conicity (EN 15302, "
        f"{1e3 * study['equivalent_conicity_amplitude_m']:g} mm): "
        + ("not covered by +-10 mm" if conicity is None else f"{conicity:.4f}")]
    if "track" in study:
        state = study["steady_curving_at_critical_speed"]
        lines.append(
            f"in a curve of radius {study['track']['radius_m']:g} m, cant "
            f"{study['track']['cant_m']:g} m; steady curving at the critical speed: "
            "wheelsets at " + ", ".join(f"{1e3 * y:+.2f} mm" for y in
                                        state["wheelset_lateral_m"])
            + " (left +), yawed " + ", ".join(f"{1e3 * a:+.3f} mrad" for a in
                                            state["wheelset_yaw_rad"])
            + f", tangential force {state['tangential_force_n']:.1f} N")
    return "\n".join(lines)


def ramp_track(track, low, high, rate, hold):
    """A straight with ``track``'s rail centre distance and rails long enough [m] for the
    ramp-down from ``high`` to ``low`` [m/s] at ``rate`` [m/s^2] after ``hold`` [s]."""
    length = 100.0 + high * (hold + (high - low) / rate)
    return straight_track(length, rail_centre_distance=track.rail_centre_distance,
                          rails=track.rails)


def nonlinear_study(vehicle, params, track, low, high, rate=GENSYS_RATE, resolution=0.5,
                    hold=2.0, options=None, model=None, progress=None) -> dict:
    """The nonlinear critical speed over ``[low, high]`` [m/s] by both methods
    (:mod:`jaxrail.stability.nonlinear`): the ramp-down from ``high`` to ``low`` at
    ``rate`` [m/s^2] after ``hold`` [s], and brute force to ``resolution`` [m/s], on a
    straight of ``track``'s rail centre distance long enough for the ramp.
    ``nonlinear_critical_speed_m_s`` is the brute force's (constant speeds, the
    definition); the ramp-down's is beside it with their relative difference."""
    check_straight(track)
    options = SolverOptions(integrator="imex") if options is None else options
    long = ramp_track(track, low, high, rate, hold)
    ramp = ramp_down(vehicle, params, long, high, low, rate=rate, hold=hold, options=options,
                     contact_model=model)
    if progress is not None:
        progress(f"ramp-down: {ramp['status']}")
    not_run = lambda why: {"status": f"not run: {why}", "critical_speed_m_s": None,  # noqa: E731
                           "bracket_m_s": None, "resolution_m_s": resolution, "runs": []}
    if ramp["attractor_at_start_speed"]["kind"] != "hunting limit cycle":
        brute = not_run(ramp["status"])
    else:
        try:
            brute = brute_force(vehicle, params, long, low, high, resolution=resolution,
                                hold=hold, options=options, contact_model=model,
                                progress=progress)
        except ValueError as error:  # e.g. its own run at ``high`` found no cycle
            brute = not_run(error)
    speeds = ramp["critical_speed_m_s"], brute["critical_speed_m_s"]
    return {
        "nonlinear_critical_speed_m_s": speeds[1],
        "nonlinear_critical_speed_km_h": None if speeds[1] is None else 3.6 * speeds[1],
        "ramp_down_critical_speed_m_s": speeds[0],
        "ramp_down_relative_to_brute_force": (None if None in speeds
                                              else speeds[0] / speeds[1] - 1.0),
        "ramp_down": ramp,
        "brute_force": brute,
    }


def format_nonlinear(study: dict) -> str:
    """The nonlinear study as lines for the terminal."""
    ramp, brute = study["ramp_down"], study["brute_force"]
    cycle = ramp["attractor_at_start_speed"]
    speed = lambda v: "not found" if v is None else f"{v:.2f} m/s ({3.6 * v:.1f} km/h)"  # noqa: E731
    lines = [f"attractor at {ramp['start_speed_m_s']:g} m/s: {cycle['kind']}"
             + (f", amplitude {1e3 * cycle['amplitude_m']:.2f} mm at "
                f"{cycle['frequency_hz']:.2f} Hz" if cycle["kind"] == "hunting limit cycle"
                else ""),
             f"ramp-down ({ramp['rate_km_h_per_s']:g} km/h per s): "
             f"{speed(ramp['critical_speed_m_s'])}, {ramp['status']}",
             f"brute force (to {brute['resolution_m_s']:g} m/s): "
             f"{speed(brute['critical_speed_m_s'])}, {brute['status']}"]
    if brute["bracket_m_s"] is not None:
        lines[-1] += (f", dies at {brute['bracket_m_s'][0]:.2f}, hunts at "
                      f"{brute['bracket_m_s'][1]:.2f} m/s")
    return "\n".join(lines)
