"""One row of the Monte Carlo table per sample: its inputs and the safety and wear
quantities of its run (host NumPy on an unbatched SimulationResult).

Columns (W wheelsets, K = 1..W leading first, SIDE = left/right):

- ``status``, ``simulated_time_s``, ``steps``;
- ``max_lateral_displacement_K_m``: max |lateral offset| of wheelset K from the
  track centreline;
- ``max_Y_over_Q_K``: max Y/Q of wheelset K's two wheels (Nadal convention,
  :func:`jaxrail.results.derailment_ratio`), instantaneous; ``max_Y_over_Q_mean_K``:
  the max over wheelset K's wheels of Y/Q over a sliding 2 m of track, as the ratio of
  the 2 m means of Y and of Q (EN 14363 evaluates Y/Q over 2 m: a flange-climb risk has
  to last, an impact peak of a few ms does not lift a wheel; the ratio of the means
  stays defined where Q drops below 1 kN for an instant and Y/Q itself does not);
  and ``nadal_limit`` for the sample's friction and a 70 deg flange;
- ``max_sum_Y_K_N``: max |Sum Y| of wheelset K, the track shifting force (the
  lateral forces of its two wheels on the rails, added in the track frame), averaged
  over a sliding 2 m of track as EN 14363 does; ``prudhomme_limit_K_N``:
  alpha (10 kN + P/3), P the wheelset's static load at t = 0 [N], alpha = 1;
- ``max_normal_force_N``: over all wheels and patches;
- ``flange_contact_fraction_K_SIDE``: fraction of the reached output times with a
  patch on the flange (contact angle above 0.6 rad);
- ``wear_number_K_SIDE_N``: the wheel's wear number T gamma = sum over patches of
  |F_x gamma_x| + |F_y gamma_y| [N = J/m], averaged over the reached output times
  (the spin moment term is left out: the creep laws give no spin moment);
- EN 14363 (:func:`en14363_row`): per check of
  :func:`jaxrail.standards.en14363.assess_channels` on straight track, a value column
  ``en14363_<quantity>_<where>[_N]`` and a ratio column (value / limit)
  ``en14363_<quantity>_<where>_ratio``: ``y_over_q_2m`` and ``qmax`` per wheel
  (``wheelset_K_SIDE``), ``sum_y_2m`` and ``sum_y_rms`` per wheelset
  (``wheelset_K``); ``en14363_passed`` (1 no assessed check fails, 0 one does) and
  ``en14363_max_ratio`` (the largest ratio of the assessed checks);
- EN 12299 (:func:`en12299_row`), for a vehicle with a ``carbody``:
  ``en12299_nmv_<point>`` the mean comfort N_MV at each floor point of
  :func:`jaxrail.standards.comfort.trailer_floor_points` (``over_leading_bogie``,
  ``centre``, ``over_trailing_bogie``), indicative from the whole 5 s blocks the
  record holds.

The standards' columns are NaN where the record is too short for them: the EN 14363
ones all when fewer than 2 m were travelled (the 2 m sliding means), the output rate
is under 40 Hz (the 20 Hz force low-pass) or a force is not finite; ``sum_y_rms``
under 100 m (its sliding rms); N_MV under one 5 s block. Their names come from the
vehicle (wheelsets, bodies), never from which values a run gave, so every row of a
study has the same columns.
"""

import re

import numpy as np

from ..results import (MIN_VERTICAL_FORCE_N, SIDES, derailment_ratio, masked_max,
                       nadal_forces, nadal_limit, summarize)
from ..standards import comfort, en14363
from ..standards.en14363_signals import sample_rate
from ..standards.from_result import comfort_states, result_channels

SLIDING_WINDOW_M = en14363.SLIDING_MEAN_WINDOW_M  # [m] of Y/Q and the track shifting force


def sliding_mean(values, window):
    """Means of ``window`` consecutive values (the whole series if it is shorter)."""
    values = np.asarray(values, dtype=np.float64)
    window = max(1, min(int(window), len(values)))
    if len(values) == 0:
        return values
    cumulative = np.concatenate([[0.0], np.cumsum(values)])
    return (cumulative[window:] - cumulative[:-window]) / window


def sliding_ratio(y, q, window):
    """Y/Q over ``window`` consecutive values as the ratio of the sliding means of ``y``
    and ``q`` [N]; NaN where the mean of ``q`` is under 1 kN."""
    mean_q = sliding_mean(q, window)
    loaded = mean_q > MIN_VERTICAL_FORCE_N
    return np.where(loaded, sliding_mean(y, window) / np.where(loaded, mean_q, 1.0), np.nan)


def prudhomme_limit(axle_load, vehicle_type="passenger"):
    """Prud'homme's limit of the track shifting force [N]: alpha (10 kN + P / 3) with
    the static wheelset load ``axle_load`` P [N]
    (:func:`jaxrail.standards.en14363.prudhomme_limit` of the wheel load P / 2)."""
    return en14363.prudhomme_limit(0.5 * np.asarray(axle_load, dtype=np.float64),
                                   vehicle_type)


def track_shifting_force(result):
    """Sum Y (T, W) [N]: the wheelset's lateral force on the track, track frame,
    positive to the left (NaN at times not reached)."""
    outward, _ = nadal_forces(result)  # on each rail, toward its field side
    return outward[:, :, 0] - outward[:, :, 1]  # the left rail's is +y, the right's -y


def wear_number(result):
    """T gamma (T, W, 2) [N] of every wheel, summed over its patches."""
    w = result.wheels
    active = np.asarray(w.active, dtype=bool)
    terms = (np.abs(np.asarray(w.creep_force_x) * np.asarray(w.creepage_x))
             + np.abs(np.asarray(w.creep_force_y) * np.asarray(w.creepage_y)))
    return np.sum(np.where(active & np.isfinite(terms), terms, 0.0), axis=3)


def _finite_max(x):
    """Largest finite value, NaN if there is none."""
    x = np.asarray(x, dtype=np.float64)
    best = masked_max(x, np.isfinite(x))
    return np.nan if best is None else best


def snake(text: str) -> str:
    """``text`` as a snake_case column name part: "(Y/Q)2m" -> "y_over_q_2m"."""
    return "_".join(re.findall(r"[a-z0-9]+", text.replace("/", " over ").lower()))


# EN 14363 checks of straight track in the table: (quantity, units) as
# en14363.assess_channels names them, per wheel and per wheelset.
EN14363_WHEEL_CHECKS = (("(Y/Q)2m", "1"), ("Qmax", "N"))
EN14363_WHEELSET_CHECKS = (("(Sum Y)2m", "N"), ("(Sum Y)rms", "N"))


def en14363_column(check: dict) -> tuple[str, str]:
    """(value column, ratio column) of an EN 14363 ``check`` (its quantity, where and
    units)."""
    base = f"en14363_{snake(check['quantity'])}_{snake(check['where'])}"
    unit = {"1": "", "N": "_N"}.get(check["units"], f"_{snake(check['units'])}")
    return base + unit, base + "_ratio"


def en14363_columns(n_wheelsets: int) -> list[str]:
    """The EN 14363 column names of a vehicle of ``n_wheelsets`` (module docstring)."""
    checks = [(q, f"wheelset {k} {side}", u) for k in range(1, n_wheelsets + 1)
              for side in SIDES for q, u in EN14363_WHEEL_CHECKS]
    checks += [(q, f"wheelset {k}", u) for k in range(1, n_wheelsets + 1)
               for q, u in EN14363_WHEELSET_CHECKS]
    names = [name for q, where, u in checks
             for name in en14363_column({"quantity": q, "where": where, "units": u})]
    return names + ["en14363_passed", "en14363_max_ratio"]


def _en14363_channels(result, body_names):
    """The run's EN 14363 channels (:func:`jaxrail.standards.from_result.result_channels`),
    None where the record cannot be assessed: fewer than 2 valid rows, forces or path
    not finite, times not uniform or under twice the force low-pass, less than 2 m
    travelled."""
    if en14363.leading_wheelset_body(body_names) is None \
            or en14363.valid_rows(result.valid) < 2:
        return None
    channels = result_channels(result, body_names)
    if not all(np.all(np.isfinite(channels[k])) for k in ("time", "distance", "y", "q")):
        return None
    try:
        rate = sample_rate(channels["time"])
    except ValueError:  # not uniform: the filters cannot run
        return None
    s = channels["distance"]
    if rate < 2.0 * en14363.FORCE_LOWPASS_HZ or s[-1] - s[0] < SLIDING_WINDOW_M:
        return None
    return channels


def en14363_row(result, speed, body_names) -> dict:
    """The EN 14363 columns (module docstring) of one run at ``speed`` [m/s], whose
    vehicle's bodies are ``body_names``. Q0 is each wheelset's mean wheel load at t = 0
    (as ``prudhomme_limit_K_N``), the permissible speed the sample's; straight track
    limits; the instability rms only over 100 m or more. NaN where not assessable."""
    n_wheelsets = np.shape(result.wheels.vertical_force)[1]
    row = dict.fromkeys(en14363_columns(n_wheelsets), np.nan)
    channels = _en14363_channels(result, body_names)
    if channels is None:
        return row
    s, first = channels["distance"], channels["q"][0]
    load = 0.5 * np.sum(first, axis=1)
    assessment = en14363.assess_channels(
        channels["time"], s, channels["y"], channels["q"],
        static_wheel_load=load if np.all(load > 0.0) else None,
        max_speed_kmh=3.6 * float(speed),
        assess_instability=bool(s[-1] - s[0] >= en14363.INSTABILITY_WINDOW_M))
    ratios = []
    for check in assessment["checks"]:
        value, ratio = en14363_column(check)
        if value in row:  # the curve-only checks (not assessed here) have no column
            row[value] = np.nan if check["value"] is None else check["value"]
            row[ratio] = np.nan if check["ratio"] is None else check["ratio"]
        if check["ratio"] is not None:
            ratios.append(check["ratio"])
    row["en14363_passed"] = float(assessment["passed"])
    row["en14363_max_ratio"] = max(ratios) if ratios else np.nan
    return row


def en12299_columns(body_names) -> list[str]:
    """The EN 12299 column names: one per floor point where the vehicle has a
    ``carbody``, none otherwise."""
    if "carbody" not in body_names:
        return []
    return [f"en12299_nmv_{snake(name)}" for name in comfort.trailer_floor_points()]


def en12299_row(result, body_names) -> dict:
    """The EN 12299 columns (module docstring) of one run whose vehicle's bodies are
    ``body_names``: N_MV at the carbody floor points, NaN for a record under one 5 s
    block or with states not finite."""
    names = en12299_columns(body_names)
    row = dict.fromkeys(names, np.nan)
    if not names:
        return row
    time, q, qdot, qddot, body = comfort_states(result, body_names)
    finite = all(np.all(np.isfinite(x[:, body])) for x in (q, qdot, qddot))
    if comfort.record_blocks(time)[1] < 1 or not finite:
        return row
    points = comfort.comfort_of_states(time, q, qdot, qddot, body)["points"]
    for name, point in zip(names, points.values()):
        row[name] = point["n_mv"]
    return row


def sample_row(result, friction, speed, body_names) -> dict:
    """The table row (without the inputs) of one unbatched run at ``speed`` [m/s] with
    ``friction``, whose vehicle's bodies are ``body_names`` (``vehicle.system.
    body_names``): see the module docstring. NaN where a quantity has no value (e.g.
    nothing reached, or a record too short for a standard's window)."""
    summary = summarize(result, friction=friction)
    valid = np.asarray(result.valid, dtype=bool)
    n_wheelsets = len(summary["wheelsets"])
    row = {"status": summary["status"], "simulated_time_s": summary["simulated_time_s"],
           "steps": summary["steps"], "nadal_limit": nadal_limit(friction)}
    t = np.asarray(result.t, dtype=np.float64)[valid]  # diffrax fills unreached times with inf
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
    window = int(round(SLIDING_WINDOW_M / max(float(speed) * dt, 1e-12)))
    sum_y = track_shifting_force(result)[valid]
    ratio = derailment_ratio(result)[valid]
    nadal_y, vertical = nadal_forces(result)
    static_vertical = vertical[0]
    nadal_y, vertical = nadal_y[valid], vertical[valid]
    tgamma = wear_number(result)[valid]
    for k in range(n_wheelsets):
        name = k + 1
        lateral = summary["wheelsets"][k]["max_lateral_displacement_m"]
        row[f"max_lateral_displacement_{name}_m"] = np.nan if lateral is None else lateral
        row[f"max_Y_over_Q_{name}"] = _finite_max(ratio[:, k, :])
        row[f"max_Y_over_Q_mean_{name}"] = _finite_max(
            [sliding_ratio(nadal_y[:, k, j], vertical[:, k, j], window)
             for j in range(2)])
        row[f"max_sum_Y_{name}_N"] = _finite_max(np.abs(sliding_mean(sum_y[:, k], window)))
        row[f"prudhomme_limit_{name}_N"] = float(prudhomme_limit(np.sum(static_vertical[k])))
    peaks = [w["max_normal_force_N"] for w in summary["wheels"]]
    row["max_normal_force_N"] = _finite_max([np.nan if p is None else p for p in peaks])
    for entry in summary["wheels"]:
        k, side = entry["wheelset"], entry["side"]
        fraction = entry["flange_contact_fraction"]
        row[f"flange_contact_fraction_{k}_{side}"] = np.nan if fraction is None else fraction
        j = SIDES.index(side)
        row[f"wear_number_{k}_{side}_N"] = (float(np.mean(tgamma[:, k - 1, j]))
                                            if len(tgamma) else np.nan)
    return row | en14363_row(result, speed, body_names) | en12299_row(result, body_names)
