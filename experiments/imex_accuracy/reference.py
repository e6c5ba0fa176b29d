"""IMEX and Tsit5 at the default tolerances against a tight reference (Tsit5 at rtol
1e-7) on the start of the paper's curve: where the two default runs differ, which one
is right.

Runs the scenario (table mode by default) for ``--duration`` seconds three times and
prints JSON: for IMEX and Tsit5 at rtol 1e-4, the largest differences from the
reference in the leading wheelset's lateral displacement [mm] and in the outer
wheel's normal force [% of its largest], overall and in ``--window`` (two times [s]).
Usage: ``python experiments/imex_accuracy/reference.py paper-curve-simplified
[--duration 5] [--window 4.3 4.6] [--contact table]``.
"""

import argparse
import dataclasses
import json

import numpy as np

from jaxrail import enable_float64

enable_float64()

from jaxrail.scenarios import load_scenario, run_scenario  # noqa: E402

OUTER = 1  # the right wheel, outer in the paper's left curve


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scenario")
    parser.add_argument("--duration", type=float, default=5.0, help="[s]")
    parser.add_argument("--window", type=float, nargs=2, default=(4.3, 4.6), help="[s]")
    parser.add_argument("--contact", choices=("online", "table"), default="table")
    args = parser.parse_args()
    runs = {}
    for label, integrator, rtol in (("reference", "tsit5", 1e-7), ("tsit5", "tsit5", 1e-4),
                                    ("imex", "imex", 1e-4)):
        scenario = dataclasses.replace(load_scenario(args.scenario), integrator=integrator,
                                       rtol=rtol, atol=rtol * 1e-3, output_rate=1000.0)
        result, *_ = run_scenario(scenario, args.duration, False, contact=args.contact)
        runs[label] = result
        print(json.dumps({"run": label, "status": result.status,
                          "steps": int(result.accepted_steps),
                          "wall_time_s": round(float(result.wall_time_s), 1)}), flush=True)
    t = np.asarray(runs["reference"].t)
    window = (t >= args.window[0]) & (t <= args.window[1])

    def lateral(r):
        return np.asarray(r.wheelset_lateral)[:, 0]

    def force(r):
        return np.nansum(np.asarray(r.wheels.normal_force)[:, 0, OUTER], axis=-1)

    scale = np.max(force(runs["reference"]))
    report = {"scenario": args.scenario, "contact": args.contact,
              "duration_s": args.duration, "window_s": list(args.window)}
    for label in ("tsit5", "imex"):
        dn = 100 * np.abs(force(runs[label]) - force(runs["reference"])) / scale
        dy = 1e3 * np.abs(lateral(runs[label]) - lateral(runs["reference"]))
        report[label] = {"max_lateral_difference_mm": float(dy.max()),
                         "max_normal_force_difference_percent": float(dn.max()),
                         "at_s": float(t[np.argmax(dn)]),
                         "in_window_percent": float(dn[window].max())}
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
