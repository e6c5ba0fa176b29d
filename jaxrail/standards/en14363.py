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

Every constant carries its source and certainty: [V-src: ...] checked against the
named public source; [R] recalled, not checked against the text of the standard (the
standard itself is not public). Clause numbers are EN 14363:2016's as recalled [R].
"""

import numpy as np

from .en14363_signals import (bandpass, check_distance, check_finite, dominant_frequency,
                              lowpass, percentile, sample_rate, sliding_mean, sliding_rms,
                              two_sided_extreme)

STANDARD = "EN 14363:2016+A1:2018"  # [V-src: BSI shop page for BS EN 14363:2016+A1:2018]

# --- Signal processing (assessment quantities of the normal measuring method) ---------
# Forces Y, Q, Sum Y: low-pass 20 Hz. [V-src: gensys.se UIC518_tests table: ">= 20 Hz"
# for Sum Y, Y/Q, Yqst and Qqst, "20 Hz" for Q] Butterworth of order 4: [R].
FORCE_LOWPASS_HZ = 20.0
FILTER_ORDER = 4
# Sliding mean over 2 m, evaluated every 0.5 m. [V-src: gensys.se UIC518_tests table;
# 2 m window also railwaynews.net on UIC 518]
SLIDING_MEAN_WINDOW_M = 2.0
SLIDING_MEAN_STEP_M = 0.5
# Percentiles of the maxima and of the quasi-static values. [V-src: gensys.se table:
# F1 = 0.15 %, F2 = 99.85 %, F0 = 50 % for Yqst, Qqst and the quasi-static
# acceleration, which that table computes without a sliding mean]
PERCENTILE_LOW, PERCENTILE_HIGH, PERCENTILE_QUASI_STATIC = 0.15, 99.85, 50.0
# Instability: Sum Y band-pass f0 +- 2 Hz [V-src: gensys.se table], sliding rms over
# 100 m every 10 m [R].
INSTABILITY_HALF_BAND_HZ = 2.0
INSTABILITY_WINDOW_M, INSTABILITY_STEP_M = 100.0, 10.0
# Where f0 is searched when the caller does not give it: a choice of this module (the
# standard takes f0 from the measured signal), spanning bogie hunting frequencies.
INSTABILITY_SEARCH_BAND_HZ = (2.5, 20.0)
# Carbody accelerations: band-pass 0.4-10 Hz for the maxima and rms [V-src: gensys.se
# table]; the quasi-static lateral acceleration through the 20 Hz low-pass [V-src: same].
CARBODY_BAND_HZ = (0.4, 10.0)

# --- Limit values ---------------------------------------------------------------------
VEHICLE_TYPES = ("passenger", "locomotive", "freight")
# Prud'homme's alpha: 1 for locomotives and passenger vehicles, 0.85 for freight wagons.
# [R] (the same values stand in jaxrail/montecarlo/summary.py)
PRUDHOMME_ALPHA = {"passenger": 1.0, "locomotive": 1.0, "freight": 0.85}
# (Y/Q)lim: 0.8 [V-src: railwaynews.net on UIC 518, "Y/Q must not exceed 0.8, window
# 2 m"], for R >= 250 m [R]; 1.2 below 250 m [R].
Y_OVER_Q_LIMIT, Y_OVER_Q_LIMIT_SMALL_RADIUS, SMALL_RADIUS_M = 0.8, 1.2, 250.0
# Qlim = 90 kN + Q0, at most 200/190/180/170/160 kN for a permissible speed up to
# 160/200/250/300 km/h and above. [R]
Q_LIMIT_OFFSET_N = 90e3
Q_LIMIT_CAPS = ((160.0, 200e3), (200.0, 190e3), (250.0, 180e3), (300.0, 170e3),
                (np.inf, 160e3))
# Quasi-static forces in curves. [R]
YQST_LIMIT_N, QQST_LIMIT_N = 60e3, 145e3
# Bogie frame lateral acceleration (simplified method, instability): rms limit
# (12 - m_bogie / 5) / 2 m/s^2, m_bogie in t. [R]
BOGIE_ACCELERATION_BASE, BOGIE_ACCELERATION_PER_T = 12.0, 0.2
# Carbody lateral acceleration limits [m/s^2]: maximum, rms, quasi-static. [R]
CARBODY_LIMITS = {"passenger": (2.5, 0.5, 1.5), "locomotive": (2.5, 0.5, 1.5),
                  "freight": (3.0, 1.3, 1.5)}

CLAUSE_SAFETY = "7.5.1"  # limit values for running safety [R]
CLAUSE_TRACK = "7.5.2"  # limit values for track loading [R]
CLAUSE_RIDE = "7.5.3"  # limit values for the running behaviour (ride) [R]
SIDES = ("left", "right")


def _vehicle_type(vehicle_type):
    if vehicle_type not in VEHICLE_TYPES:
        raise ValueError(f"vehicle_type: expected one of {', '.join(VEHICLE_TYPES)}, got "
                         f"{vehicle_type!r}")
    return vehicle_type


def prudhomme_limit(static_wheel_load, vehicle_type="passenger"):
    """(Sum Y)2m,lim = alpha (10 kN + 2 Q0 / 3) [N], ``static_wheel_load`` Q0 [N] (2 Q0
    the static axle load); alpha = 1 for passenger vehicles and locomotives, 0.85 for
    freight wagons. Running safety (track shifting), clause 7.5.1, every track zone."""
    alpha = PRUDHOMME_ALPHA[_vehicle_type(vehicle_type)]
    return alpha * (10e3 + 2.0 * np.asarray(static_wheel_load, dtype=np.float64) / 3.0)


def instability_limit(static_wheel_load, vehicle_type="passenger"):
    """(Sum Y)rms,lim = (Sum Y)2m,lim / 2 [N]: running stability, clause 7.5.1, on
    straight track and large radius curves."""
    return 0.5 * prudhomme_limit(static_wheel_load, vehicle_type)


def y_over_q_limit(curve_radius=None):
    """(Y/Q)lim: 0.8 on straight track and in curves of radius >= 250 m, 1.2 in curves
    below 250 m (``curve_radius`` [m], None or inf for straight track). Running safety
    (flange climbing), clause 7.5.1."""
    if curve_radius is not None and curve_radius < SMALL_RADIUS_M:
        return Y_OVER_Q_LIMIT_SMALL_RADIUS
    return Y_OVER_Q_LIMIT


def vertical_force_limit(static_wheel_load, max_speed_kmh):
    """Qlim = 90 kN + Q0 [N], at most 200 kN (permissible speed V <= 160 km/h), 190 kN
    (<= 200), 180 kN (<= 250), 170 kN (<= 300), 160 kN (above). Track loading, clause
    7.5.2."""
    cap = next(c for v, c in Q_LIMIT_CAPS if max_speed_kmh <= v)
    return np.minimum(Q_LIMIT_OFFSET_N + np.asarray(static_wheel_load, dtype=np.float64),
                      cap)


def bogie_frame_acceleration_limit(bogie_mass_kg):
    """Limit of the 100 m sliding rms of the bogie frame lateral acceleration,
    (12 - m_bogie / 5) / 2 [m/s^2] with m_bogie in t: instability, simplified measuring
    method, clause 7.5.1."""
    tonnes = np.asarray(bogie_mass_kg, dtype=np.float64) / 1e3
    return 0.5 * (BOGIE_ACCELERATION_BASE - BOGIE_ACCELERATION_PER_T * tonnes)


def carbody_acceleration_limits(vehicle_type="passenger"):
    """{"max", "rms", "qst"} [m/s^2]: limits of the carbody lateral acceleration's
    maximum (0.4-10 Hz), rms and quasi-static value (curves). Running behaviour,
    clause 7.5.3."""
    peak, rms, qst = CARBODY_LIMITS[_vehicle_type(vehicle_type)]
    return {"max": peak, "rms": rms, "qst": qst}


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

REQUIRED_DATASETS = ("time", "valid", "contact/lateral_force", "contact/vertical_force",
                     "bodies/q")


def leading_wheelset_body(names):
    """Index in ``names`` (the bodies' names, in order) of the leading wheelset's body:
    the one named ``wheelset`` or ``wheelset_<k>`` with the smallest k; None if none."""
    candidates = []
    for i, name in enumerate(names):
        head, _, tail = str(name).lower().partition("_")
        if head == "wheelset" and (tail == "" or tail.isdigit()):
            candidates.append((int(tail) if tail else 0, i))
    return min(candidates)[1] if candidates else None


def find_wheelset_body(names, wheelset_body, where):
    """(index of the leading wheelset's body, how it was found) from the bodies'
    ``names`` (None if unnamed), unless ``wheelset_body`` gives it; ``where`` names
    the names' source in the error."""
    if wheelset_body is not None:
        return int(wheelset_body), "argument wheelset_body"
    i = None if names is None else leading_wheelset_body(names)
    if i is None:
        raise ValueError(f"wheelset_body: no body named 'wheelset' or 'wheelset_<k>' "
                         f"in {where} ({'none given' if names is None else list(names)}); "
                         "pass the leading wheelset's body index")
    return i, f"{where}: {names[i]!r}"


def valid_rows(valid) -> int:
    """How many rows come before the first False of ``valid`` (T,) (all when none is):
    an early stop ends the record."""
    valid = np.asarray(valid, dtype=bool)
    return len(valid) if np.all(valid) else int(np.argmin(valid))


def travelled_distance(centre):
    """Distance travelled [m] (T,) from 0: the cumulative horizontal path of a point
    whose global (x, y) [m] at each sample is ``centre`` (T, 2)."""
    steps = np.hypot(*np.diff(np.asarray(centre, dtype=np.float64), axis=0).T)
    return np.concatenate([[0.0], np.cumsum(steps)])


def record_channels(time, valid, lateral_force, vertical_force, centre):
    """``{"time", "distance", "y", "q", "rows", "total_rows"}``: the channels of
    :func:`assess_channels` from a run's outputs, over the rows before the first
    ``valid`` False. ``lateral_force``, ``vertical_force`` (T, W, 2) [N] are the
    contact outputs (on the wheel from the rail, track frame: docs/results.md), so Y
    = -lateral_force and Q = vertical_force; ``centre`` (T, 2) [m] is the leading
    wheelset centre's global (x, y), whose path is the distance travelled. A
    ValueError when fewer than 2 rows are valid."""
    rows = valid_rows(valid)
    if rows < 2:
        raise ValueError(f"fewer than 2 valid rows ({rows})")
    return {"time": np.asarray(time, dtype=np.float64)[:rows],
            "distance": travelled_distance(np.asarray(centre)[:rows]),
            "y": -np.asarray(lateral_force, dtype=np.float64)[:rows],
            "q": np.asarray(vertical_force, dtype=np.float64)[:rows],
            "rows": rows, "total_rows": len(np.asarray(valid))}


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
