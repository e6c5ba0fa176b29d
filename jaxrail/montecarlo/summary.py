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
  (the spin moment term is left out: the creep laws give no spin moment).
"""

import numpy as np

from ..results import (MIN_VERTICAL_FORCE_N, SIDES, _masked_max, derailment_ratio,
                       nadal_forces, nadal_limit, summarize)
from ..standards import en14363

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
    best = _masked_max(x, np.isfinite(x))
    return np.nan if best is None else best


def sample_row(result, friction, speed) -> dict:
    """The table row (without the inputs) of one unbatched run: see the module
    docstring. NaN where a quantity has no value (e.g. nothing reached)."""
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
    return row
