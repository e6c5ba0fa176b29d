"""EN 14363 (2016 edition and its amendment A1:2018): the standard's numbers, its
filters and windows of the assessment quantities and its limit values, with their
sources (:mod:`jaxrail.standards.en14363` computes the quantities and checks them).

Every constant carries its source and certainty: [V-src: ...] checked against the
named public source; [R] recalled, not checked against the text of the standard (the
standard itself is not public). Clause numbers are EN 14363:2016's as recalled [R].
"""

import numpy as np

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
