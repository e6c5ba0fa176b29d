"""EN 14363 (2016 edition and its amendment A1:2018) assessment quantities, limit values
and a pass/fail table, from the channels of a simulated run or a jaxrail results file.

Plain NumPy float64 on the host. What a simulated run can claim is in
docs/standards.md: EN 14363's on-track measuring method is a test
procedure on a real vehicle; here its quantities are computed from a simulated run's
forces in the same way, as the standard's simulation route does, and the result is an
estimate for one run on one track, not an acceptance.

Conventions (docs/results.md): Y is the lateral force of the wheel on the rail,
positive towards the field side (a flanging wheel pushes its rail outward, Y > 0); Q is
the vertical wheel force, positive down on the rail. Axes of Y and Q: time, wheelset
(0 = leading), wheel (0 left, 1 right, in the direction of travel). Sum Y, the track
shifting force of a wheelset, is Y_left - Y_right in the track frame (positive left).

The standard's numbers (filters, windows, limit values, each with its source) are
:mod:`.en14363_limits`, the channels of a run's record :mod:`.en14363_record`; their
names are importable from here as well.
"""

import numpy as np

from .en14363_limits import (STANDARD, FORCE_LOWPASS_HZ, FILTER_ORDER,
                             SLIDING_MEAN_WINDOW_M, SLIDING_MEAN_STEP_M, PERCENTILE_LOW,
                             PERCENTILE_HIGH, PERCENTILE_QUASI_STATIC,
                             INSTABILITY_HALF_BAND_HZ, INSTABILITY_WINDOW_M,
                             INSTABILITY_STEP_M, INSTABILITY_SEARCH_BAND_HZ,
                             CARBODY_BAND_HZ, VEHICLE_TYPES, PRUDHOMME_ALPHA,
                             Y_OVER_Q_LIMIT, Y_OVER_Q_LIMIT_SMALL_RADIUS,
                             SMALL_RADIUS_M, Q_LIMIT_OFFSET_N, Q_LIMIT_CAPS,
                             YQST_LIMIT_N, QQST_LIMIT_N, BOGIE_ACCELERATION_BASE,
                             BOGIE_ACCELERATION_PER_T, CARBODY_LIMITS, CLAUSE_SAFETY,
                             CLAUSE_TRACK, CLAUSE_RIDE, SIDES, _vehicle_type,
                             prudhomme_limit, instability_limit, y_over_q_limit,
                             vertical_force_limit, bogie_frame_acceleration_limit,
                             carbody_acceleration_limits)
from .en14363_record import (REQUIRED_DATASETS, leading_wheelset_body,
                             find_wheelset_body, valid_rows, travelled_distance,
                             record_channels)
from .en14363_signals import (bandpass, check_distance, check_finite, dominant_frequency,
                              lowpass, percentile, sample_rate, sliding_mean, sliding_rms,
                              two_sided_extreme)


# --- Assessment -----------------------------------------------------------------------

def _num(x):
    x = float(x)
    return x if np.isfinite(x) else None


def _check(criterion, quantity, where, value, limit, units, clause, statistic,
           conditions, applicable=True, fails=False):
    """One row of the assessment; ``fails`` marks a check failed whatever its value."""
    value, limit = _num(value), (None if limit is None else _num(limit))
    assessed = applicable and value is not None and limit is not None
    passed = bool(value <= limit) and not fails if assessed else (False if fails else None)
    return {"criterion": criterion, "quantity": quantity, "where": where,
            "value": value, "limit": limit, "units": units,
            "margin": limit - value if assessed else None,
            "ratio": value / limit if assessed and limit != 0.0 else None,
            "passed": passed,
            "clause": f"{STANDARD} {clause}", "statistic": statistic,
            "conditions": conditions}


def _channels(name, values, n_samples):
    """An optional acceleration channel set as (T, k) float64, or None."""
    if values is None:
        return None
    a = np.asarray(values, dtype=np.float64)
    a = a[:, None] if a.ndim == 1 else a
    if a.ndim != 2 or a.shape[0] != n_samples:
        raise ValueError(f"{name}: expected shape ({n_samples},) or ({n_samples}, k), got "
                         f"{np.shape(values)}")
    return check_finite(name, a)


def _forces(name, values, n_samples):
    if values is None:
        raise ValueError(f"{name}: missing (the wheel forces are required)")
    x = np.asarray(values, dtype=np.float64)
    if x.ndim != 3 or x.shape[0] != n_samples or x.shape[2] != 2:
        raise ValueError(f"{name}: expected shape ({n_samples}, wheelsets, 2), got "
                         f"{x.shape}")
    return check_finite(name, x)


def _validate(time, distance, y, q, options):
    """Every input checked before any computation: (sample rate, distance, y, q, bogie
    frame and carbody channels or None, static wheel loads or None)."""
    _vehicle_type(options["vehicle_type"])
    if time is None or distance is None:
        raise ValueError("time and distance: both are required")
    rate = sample_rate(time)
    n = len(np.asarray(time))
    if rate < 2.0 * FORCE_LOWPASS_HZ:
        raise ValueError(f"time: sample rate {rate:.4g} Hz is below twice the "
                         f"{FORCE_LOWPASS_HZ:g} Hz low-pass of the forces")
    y, q = _forces("y (lateral force Y)", y, n), _forces("q (vertical force Q)", q, n)
    if y.shape != q.shape:
        raise ValueError(f"y and q: shapes differ, {y.shape} and {q.shape}")
    bogie = _channels("bogie_frame_acceleration", options["bogie_frame_acceleration"], n)
    carbody = _channels("carbody_acceleration", options["carbody_acceleration"], n)
    if bogie is not None:
        longest, what = INSTABILITY_WINDOW_M, "the bogie frame's 100 m sliding rms"
    elif options["assess_instability"]:
        longest, what = INSTABILITY_WINDOW_M, ("the 100 m sliding rms of the instability "
                                               "criterion (assess_instability=False "
                                               "skips it)")
    else:
        longest, what = SLIDING_MEAN_WINDOW_M, "the 2 m sliding mean"
    s = check_distance(distance, n, longest, what)
    radius = options["curve_radius"]
    if radius is not None and not radius > 0.0:
        raise ValueError(f"curve_radius: must be positive (None or inf for straight "
                         f"track), got {radius!r} m")
    load = options["static_wheel_load"]
    if load is not None:
        load = np.broadcast_to(np.asarray(load, dtype=np.float64), (y.shape[1],))
        if not np.all(np.isfinite(load) & (load > 0.0)):
            raise ValueError(f"static_wheel_load: must be positive and finite [N], one "
                             f"value or one per wheelset ({y.shape[1]}), got {load}")
    speed = options["max_speed_kmh"]
    if speed is not None and not (np.isfinite(speed) and speed > 0.0):
        raise ValueError(f"max_speed_kmh: must be positive, got {speed!r}")
    f0 = options["instability_frequency"]
    if f0 is not None and not (INSTABILITY_HALF_BAND_HZ < f0
                               < 0.5 * rate - INSTABILITY_HALF_BAND_HZ):
        raise ValueError(f"instability_frequency: f0 +- {INSTABILITY_HALF_BAND_HZ:g} Hz "
                         f"must lie between 0 and the Nyquist frequency {0.5 * rate:g} "
                         f"Hz, got f0 = {f0!r} Hz")
    mass = options["bogie_mass_kg"]
    if mass is not None and not 0.0 < mass < 60e3:
        raise ValueError(f"bogie_mass_kg: must lie in (0, 60000) kg (the limit 12 - m/5 "
                         f"is positive below 60 t), got {mass!r}")
    if carbody is not None and 0.5 * rate <= CARBODY_BAND_HZ[1]:
        raise ValueError(f"carbody_acceleration: sample rate {rate:.4g} Hz cannot carry "
                         f"the {CARBODY_BAND_HZ[1]:g} Hz band edge")
    return rate, s, y, q, bogie, carbody, load


def _instability(x, rate, s, f0):
    """(f0 used [Hz], largest 100 m sliding rms) of a channel (T,)."""
    if f0 is None:
        top = 0.5 * rate - 2.0 * INSTABILITY_HALF_BAND_HZ  # keeps f0 + 2 Hz below Nyquist
        band = (INSTABILITY_SEARCH_BAND_HZ[0], min(INSTABILITY_SEARCH_BAND_HZ[1], top))
        f0 = dominant_frequency(x, rate, band)
    filtered = bandpass(x, rate, f0 - INSTABILITY_HALF_BAND_HZ,
                        f0 + INSTABILITY_HALF_BAND_HZ, FILTER_ORDER)
    _, rms = sliding_rms(filtered, s, INSTABILITY_WINDOW_M, INSTABILITY_STEP_M)
    return f0, float(np.max(rms))


def assess_channels(time, distance, y, q, *, vehicle_type="passenger",
                    static_wheel_load=None, max_speed_kmh=None, curve_radius=None,
                    instability_frequency=None, assess_instability=True,
                    bogie_frame_acceleration=None, bogie_mass_kg=None,
                    carbody_acceleration=None) -> dict:
    """EN 14363 assessment of one run from its channels; a JSON-ready dict.

    **Arguments:**

    - ``time``: (T,) [s], uniformly sampled; ``distance``: (T,) distance travelled [m].
    - ``y``, ``q``: (T, W, 2) [N], Y and Q of every wheel (module docstring).
    - ``vehicle_type``: ``"passenger"``, ``"locomotive"`` or ``"freight"``.
    - ``static_wheel_load``: Q0 [N], one value or one per wheelset; None: the mean Q of
      each wheelset over the record (an estimate, said in ``notes``).
    - ``max_speed_kmh``: permissible speed for Qlim's cap; None: the run's top speed.
    - ``curve_radius``: [m] of the section, None (or inf) for straight track; a finite
      radius selects the curve checks (Yqst, Qqst, quasi-static acceleration) and, below
      250 m, (Y/Q)lim = 1.2.
    - ``instability_frequency``: f0 [Hz]; None: the spectral peak of each channel in
      :data:`INSTABILITY_SEARCH_BAND_HZ`. ``assess_instability``: compute the 100 m rms
      of Sum Y (needs 100 m of record).
    - ``bogie_frame_acceleration``, ``carbody_acceleration``: (T,) or (T, k) lateral
      accelerations [m/s^2]; ``bogie_mass_kg`` gives the bogie frame limit.

    Returns ``{"standard", "vehicle", "record", "checks", "passed", "notes"}``: each
    check has its criterion, quantity, where, value, limit, units, margin (limit -
    value), ratio (value / limit), passed (None where not assessed), clause, statistic
    and conditions. ``passed`` is True when no assessed check fails.
    """
    options = dict(vehicle_type=vehicle_type, static_wheel_load=static_wheel_load,
                   max_speed_kmh=max_speed_kmh, curve_radius=curve_radius,
                   instability_frequency=instability_frequency,
                   assess_instability=assess_instability,
                   bogie_frame_acceleration=bogie_frame_acceleration,
                   bogie_mass_kg=bogie_mass_kg, carbody_acceleration=carbody_acceleration)
    rate, s, y, q, bogie, carbody, load = _validate(time, distance, y, q, options)
    t = np.asarray(time, dtype=np.float64)
    notes = []
    curve = curve_radius is not None and np.isfinite(curve_radius)
    speed_kmh = 3.6 * np.gradient(s, t)
    yf = lowpass(y, rate, FORCE_LOWPASS_HZ, FILTER_ORDER)
    qf = lowpass(q, rate, FORCE_LOWPASS_HZ, FILTER_ORDER)
    if load is None:
        load = np.mean(qf, axis=(0, 2))
        notes.append("static wheel load Q0 estimated as each wheelset's mean Q over the "
                     "record; give static_wheel_load for the vehicle's weighed value")
    if max_speed_kmh is None:
        max_speed_kmh = float(np.max(speed_kmh))
        notes.append(f"Qlim capped for the run's top speed {max_speed_kmh:.1f} km/h; give "
                     "max_speed_kmh for the vehicle's permissible speed")
    track = ("straight track or large radius curve" if not curve
             else f"curve of radius {curve_radius:g} m")
    mean_2m = (f"{SLIDING_MEAN_WINDOW_M:g} m sliding mean every {SLIDING_MEAN_STEP_M:g} "
               f"m, {FORCE_LOWPASS_HZ:g} Hz low-pass")
    checks = []
    ratio = np.where(qf > 0.0, yf / np.where(qf > 0.0, qf, 1.0), np.nan)
    _, ratio_2m = sliding_mean(ratio, s, SLIDING_MEAN_WINDOW_M, SLIDING_MEAN_STEP_M)
    y_over_q = percentile(ratio_2m, PERCENTILE_HIGH)
    unloaded = np.sum(~np.isfinite(ratio_2m), axis=0)
    q_max = percentile(qf, PERCENTILE_HIGH)
    y_qst, q_qst = percentile(yf, PERCENTILE_QUASI_STATIC), percentile(
        qf, PERCENTILE_QUASI_STATIC)
    q_lim = vertical_force_limit(load, max_speed_kmh)
    for k in range(y.shape[1]):
        for j, side in enumerate(SIDES):
            where = f"wheelset {k + 1} {side}"
            checks.append(_check(
                "running safety", "(Y/Q)2m", where, y_over_q[k, j],
                y_over_q_limit(curve_radius), "1", CLAUSE_SAFETY,
                f"{PERCENTILE_HIGH:g} % of the {mean_2m}",
                f"{track}; (Y/Q)lim 0.8 for R >= 250 m, 1.2 below",
                fails=bool(unloaded[k, j])))
            if unloaded[k, j]:
                notes.append(f"{where}: Q <= 0 (wheel unloaded) inside "
                             f"{int(unloaded[k, j])} windows of 2 m: Y/Q fails")
            checks.append(_check(
                "track loading", "Qmax", where, q_max[k, j], q_lim[k], "N", CLAUSE_TRACK,
                f"{PERCENTILE_HIGH:g} % of Q, {FORCE_LOWPASS_HZ:g} Hz low-pass",
                f"Qlim = 90 kN + Q0, capped for {max_speed_kmh:.0f} km/h"))
            for name, value, limit in (("Yqst", y_qst[k, j], YQST_LIMIT_N),
                                       ("Qqst", q_qst[k, j], QQST_LIMIT_N)):
                checks.append(_check(
                    "track loading", name, where, value, limit, "N", CLAUSE_TRACK,
                    f"{PERCENTILE_QUASI_STATIC:g} % value, {FORCE_LOWPASS_HZ:g} Hz "
                    "low-pass", "curves (small radius); not assessed on straight track",
                    applicable=curve))
    sum_y = yf[:, :, 0] - yf[:, :, 1]
    _, sum_y_2m = sliding_mean(sum_y, s, SLIDING_MEAN_WINDOW_M, SLIDING_MEAN_STEP_M)
    sum_y_max = two_sided_extreme(sum_y_2m, PERCENTILE_LOW, PERCENTILE_HIGH)
    frequencies = []
    for k in range(y.shape[1]):
        where = f"wheelset {k + 1}"
        checks.append(_check(
            "running safety", "(Sum Y)2m", where, sum_y_max[k],
            prudhomme_limit(load[k], vehicle_type), "N", CLAUSE_SAFETY,
            f"max(|{PERCENTILE_LOW:g} %|, |{PERCENTILE_HIGH:g} %|) of the {mean_2m}",
            f"Prud'homme, alpha = {PRUDHOMME_ALPHA[vehicle_type]:g} ({vehicle_type})"))
        if assess_instability:
            f0, rms = _instability(y[:, k, 0] - y[:, k, 1], rate, s, instability_frequency)
            frequencies.append(_num(f0))
            checks.append(_check(
                "running safety", "(Sum Y)rms", where, rms,
                instability_limit(load[k], vehicle_type), "N", CLAUSE_SAFETY,
                f"largest {INSTABILITY_WINDOW_M:g} m sliding rms every "
                f"{INSTABILITY_STEP_M:g} m, band-pass f0 +- {INSTABILITY_HALF_BAND_HZ:g} "
                f"Hz, f0 = {f0:.2f} Hz", "instability: straight track and large radius "
                "curves; limit (Sum Y)2m,lim / 2"))
    if bogie is not None:
        limit = None if bogie_mass_kg is None else bogie_frame_acceleration_limit(
            bogie_mass_kg)
        if limit is None:
            notes.append("bogie frame acceleration: no bogie_mass_kg, no limit")
        for k in range(bogie.shape[1]):
            f0, rms = _instability(bogie[:, k], rate, s, instability_frequency)
            checks.append(_check(
                "running safety", "bogie frame y''+ rms", f"bogie frame channel {k + 1}",
                rms, limit, "m/s^2", CLAUSE_SAFETY,
                f"largest {INSTABILITY_WINDOW_M:g} m sliding rms every "
                f"{INSTABILITY_STEP_M:g} m, band-pass f0 +- {INSTABILITY_HALF_BAND_HZ:g} "
                f"Hz, f0 = {f0:.2f} Hz", "instability, simplified measuring method; "
                "limit (12 - m_bogie[t] / 5) / 2"))
    if carbody is not None:
        limits = carbody_acceleration_limits(vehicle_type)
        band = bandpass(carbody, rate, *CARBODY_BAND_HZ, FILTER_ORDER)
        quasi_static = percentile(lowpass(carbody, rate, FORCE_LOWPASS_HZ, FILTER_ORDER),
                                  PERCENTILE_QUASI_STATIC)
        peak = two_sided_extreme(band, PERCENTILE_LOW, PERCENTILE_HIGH)
        rms = np.sqrt(np.mean(band ** 2, axis=0))
        where_band = f"band-pass {CARBODY_BAND_HZ[0]:g}-{CARBODY_BAND_HZ[1]:g} Hz"
        for k in range(carbody.shape[1]):
            where = f"carbody channel {k + 1}"
            checks.append(_check(
                "running behaviour", "carbody y''* max", where, peak[k], limits["max"],
                "m/s^2", CLAUSE_RIDE, f"max(|{PERCENTILE_LOW:g} %|, "
                f"|{PERCENTILE_HIGH:g} %|), {where_band}", f"{vehicle_type} limits"))
            checks.append(_check(
                "running behaviour", "carbody y''* rms", where, rms[k], limits["rms"],
                "m/s^2", CLAUSE_RIDE, f"rms over the record, {where_band}",
                f"{vehicle_type} limits"))
            checks.append(_check(
                "running behaviour", "carbody y''*qst", where, abs(quasi_static[k]),
                limits["qst"], "m/s^2", CLAUSE_RIDE,
                f"|{PERCENTILE_QUASI_STATIC:g} % value|, {FORCE_LOWPASS_HZ:g} Hz low-pass",
                "curves; not assessed on straight track", applicable=curve))
    failed = [c for c in checks if c["passed"] is False]
    return {
        "standard": STANDARD,
        "method": ("normal measuring method quantities (wheel forces Y, Q) computed from "
                   "a simulated run; one run is one test section, not the standard's "
                   "statistical evaluation over a test zone"),
        "vehicle": {"type": vehicle_type,
                    "static_wheel_load_N": [float(x) for x in load],
                    "max_speed_kmh": float(max_speed_kmh),
                    "curve_radius_m": None if not curve else float(curve_radius),
                    "bogie_mass_kg": (None if bogie_mass_kg is None
                                      else float(bogie_mass_kg))},
        "record": {"duration_s": float(t[-1] - t[0]), "distance_m": float(s[-1] - s[0]),
                   "sample_rate_hz": float(rate),
                   "mean_speed_kmh": float(3.6 * (s[-1] - s[0]) / (t[-1] - t[0])),
                   "instability_frequency_hz": frequencies},
        "checks": checks,
        "passed": not failed,
        "failed": [f"{c['quantity']} {c['where']}" for c in failed],
        "notes": notes,
    }


_UNITS = {"N": (1e-3, "kN", "{:.1f}"), "m/s^2": (1.0, "m/s^2", "{:.3f}"),
          "1": (1.0, "", "{:.3f}")}


def format_table(assessment) -> str:
    """A plain-text table of ``assessment`` (:func:`assess_channels`): one row per check
    with its value, limit, margin (limit - value), ratio and result, then the notes."""
    header = ("criterion", "quantity", "where", "value", "limit", "margin", "ratio",
              "result", "clause")
    rows = []
    for c in assessment["checks"]:
        scale, unit, fmt = _UNITS.get(c["units"], (1.0, c["units"], "{:.4g}"))

        def show(x, scale=scale, unit=unit, fmt=fmt):
            return "-" if x is None else fmt.format(x * scale) + (f" {unit}" * bool(unit))

        result = {True: "pass", False: "FAIL", None: "n/a"}[c["passed"]]
        rows.append((c["criterion"], c["quantity"], c["where"], show(c["value"]),
                     show(c["limit"]), show(c["margin"]),
                     "-" if c["ratio"] is None else f"{c['ratio']:.2f}", result,
                     c["clause"].split()[-1]))
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    lines = [f"{assessment['standard']}: "
             + ("PASS" if assessment["passed"] else "FAIL")
             + f" ({sum(c['passed'] is not None for c in assessment['checks'])} checks "
               f"assessed, {len(assessment['failed'])} failed)"]
    for r in [header, tuple("-" * w for w in widths), *rows]:
        lines.append("  ".join(cell.ljust(w) for cell, w in zip(r, widths)).rstrip())
    lines += [f"note: {n}" for n in assessment["notes"]]
    return "\n".join(lines)


# --- The results file -----------------------------------------------------------------

def assess_record(channels, status, **options) -> dict:
    """:func:`assess_channels` of ``channels`` (:func:`record_channels`) with
    ``options``, whose acceleration channels have the run's ``total_rows`` rows (cut to
    the valid ones here); a note names an early stop (``status``)."""
    rows, total = channels["rows"], channels["total_rows"]
    for name in ("bogie_frame_acceleration", "carbody_acceleration"):
        if options.get(name) is not None:
            a = np.asarray(options[name], dtype=np.float64)
            if a.shape[0] != total:
                raise ValueError(f"{name}: expected {total} rows like the run, got "
                                 f"shape {a.shape}")
            options[name] = a[:rows]
    out = assess_channels(channels["time"], channels["distance"], channels["y"],
                          channels["q"], **options)
    if rows < total:
        out["notes"].append(f"the run stopped early ({status}): {rows} of {total} rows")
    return out


def assess_file(path, *, wheelset_body=None, **options) -> dict:
    """EN 14363 assessment of a jaxrail HDF5 results file (docs/results.md).

    Reads ``time``, ``valid``, ``contact/lateral_force`` (Y = -lateral_force),
    ``contact/vertical_force`` (Q) and ``bodies/q``; a ValueError names every one that
    is missing. Only the rows before the first ``valid = 0`` are used (an early stop
    ends the record). The distance travelled is the cumulative horizontal path of the
    leading wheelset's centre: body ``wheelset_body`` of ``bodies/q`` or, without it, the
    body named ``wheelset`` or ``wheelset_<k>`` with the smallest k in the dataset's
    ``body_names`` attribute. ``options`` are those of :func:`assess_channels`;
    acceleration channels given there have the file's T rows. The result adds
    ``"file": {"path", "status", "rows_used", "wheelset_body"}``.
    :func:`jaxrail.standards.from_result.assess_result` does the same for a
    :class:`jaxrail.simulation.SimulationResult` in memory. A ValueError names ``path``
    when it is missing or not an HDF5 file (:func:`jaxrail.results.open_results`).
    """
    from ..results import open_results

    with open_results(path) as f:
        missing = [name for name in REQUIRED_DATASETS if name not in f]
        if missing:
            raise ValueError(f"{path}: missing dataset(s) {', '.join(missing)} (a jaxrail "
                             "results file, docs/results.md, has them)")
        names = f["bodies/q"].attrs.get("body_names")
        if names is not None:
            names = [n.decode() if isinstance(n, bytes) else str(n) for n in names]
        body, found = find_wheelset_body(names, wheelset_body, "bodies/q body_names")
        q_bodies = f["bodies/q"]
        if q_bodies.ndim != 3 or not 0 <= body < q_bodies.shape[1]:
            raise ValueError(f"wheelset_body: {body} is not a body of bodies/q, shape "
                             f"{q_bodies.shape}")
        try:
            channels = record_channels(f["time"][()], f["valid"][()],
                                       f["contact/lateral_force"][()],
                                       f["contact/vertical_force"][()],
                                       q_bodies[:, body, :2])
        except ValueError as error:
            raise ValueError(f"{path}: {error}") from None
        status = f.attrs.get("status", "")
        status = status.decode() if isinstance(status, bytes) else str(status)
    out = assess_record(channels, status, **options)
    out["file"] = {"path": str(path), "status": status, "rows_used": channels["rows"],
                   "wheelset_body": body, "wheelset_body_from": found}
    return out
