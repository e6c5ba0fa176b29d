"""IMEX against the explicit Tsit5 reference on straight track: the decay of the
trailer's lateral motion from the 2 mm misalignment (built-in scenario ``straight``,
10 s at 18.3 m/s, rtol 1e-4 for both).

The decay is measured on the leading wheelset's lateral displacement y(t): its
successive extrema (each half-period's largest |y|), and the decay rate sigma [1/s]
of a straight-line fit of log|y| at the extrema against time (|y| ~ exp(-sigma t)).
Prints JSON per integrator (status, steps, wall time, extrema, sigma) and the
differences: sigma's relative difference, the largest difference of the extrema
[mm] and of y(t) [mm].
Usage: ``python experiments/imex_accuracy/run.py [--contact online|table]
[--duration 10]``.
"""

import argparse
import dataclasses
import json

import numpy as np

from jaxrail import enable_float64

enable_float64()

from jaxrail.scenarios import load_scenario, run_scenario  # noqa: E402


def extrema(t, y):
    """Times and values of the largest |y| between successive zero crossings of y."""
    sign = np.sign(y)
    cuts = np.flatnonzero(sign[1:] != sign[:-1]) + 1
    found = []
    for a, b in zip(np.r_[0, cuts], np.r_[cuts, len(y)]):
        if b - a >= 3 and a > 0 and b < len(y):  # whole half-periods only
            k = a + int(np.argmax(np.abs(y[a:b])))
            found.append((float(t[k]), float(y[k])))
    return found


def decay_rate(found):
    """sigma [1/s] of |y| ~ exp(-sigma t) fitted through the extrema."""
    times, values = np.array(found).T
    return float(-np.polyfit(times, np.log(np.abs(values)), 1)[0])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--contact", choices=("online", "table"), default="table")
    parser.add_argument("--duration", type=float, default=None, help="[s] (default 10)")
    args = parser.parse_args()
    report, runs = {"scenario": "straight", "contact": args.contact}, {}
    for integrator in ("tsit5", "imex"):
        scenario = dataclasses.replace(load_scenario("straight"), integrator=integrator,
                                       output_rate=500.0)
        result, *_ = run_scenario(scenario, args.duration, False, contact=args.contact)
        t, y = np.asarray(result.t), np.asarray(result.wheelset_lateral)[:, 0]
        found = extrema(t, y)
        runs[integrator] = (y, found)
        report[integrator] = {
            "status": result.status, "steps_accepted": int(result.accepted_steps),
            "wall_time_s": round(float(result.wall_time_s), 1),
            "extrema_s_mm": [(round(a, 3), round(1e3 * b, 4)) for a, b in found],
            "decay_rate_per_s": decay_rate(found)}
        print(json.dumps(report[integrator]), flush=True)
    (y0, e0), (y1, e1) = runs["tsit5"], runs["imex"]
    n = min(len(e0), len(e1))
    report["decay_rate_relative_difference"] = (report["imex"]["decay_rate_per_s"]
                                                / report["tsit5"]["decay_rate_per_s"] - 1.0)
    report["max_extremum_difference_mm"] = float(1e3 * np.max(np.abs(
        np.array(e0[:n])[:, 1] - np.array(e1[:n])[:, 1])))
    report["max_lateral_difference_mm"] = float(1e3 * np.max(np.abs(y0 - y1)))
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
