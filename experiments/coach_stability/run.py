"""The complete coach's critical speed with and without its yaw dampers, and the
gradient of the linear critical speed in the yaw dampers' damping against central
differences.

The coach (`jaxrail/vehicles/data/coach.toml`, the Manchester benchmark vehicle 1 with
air springs, yaw dampers, lateral dampers, anti-roll bar, bump stops and traction rods)
on ideal straight track, S1002 on UIC60 1:40, friction 0.4, the contact table.
"Without yaw dampers" sets their series stiffness to 1 N/m: they stay in the model and
carry no force (a Maxwell element's force is at most k_s times its deflection).

Writes ``results.json`` beside this file (``--out`` to change it) and prints it.
Usage: ``python experiments/coach_stability/run.py [--nonlinear LO:HI] [--out FILE]``.
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path

import jaxrail

jaxrail.enable_float64()

from jaxrail.scenarios import parse_scenario  # noqa: E402
from jaxrail.stability.critical import LinearStability  # noqa: E402
from jaxrail.stability.report import nonlinear_options, nonlinear_study, speed_range  # noqa: E402
from jaxrail.vehicles import contact_model, get_values, set_values  # noqa: E402

SCENARIO = """
name = "coach-straight"
description = "the complete coach on ideal straight track"
[vehicle]
model = "coach"
[contact]
friction = 0.4
[track]
segments = [{ kind = "straight", length = 3000.0 }]
[run]
speed = 40.0
duration = 10.0
[solver]
rtol = 1e-4
atol = 1e-7
integrator = "imex"
"""
YAW = "yaw_damper.damping"
SERIES = "yaw_damper.series_stiffness"
SPEEDS = (10.0, 250.0)  # [m/s] the range searched for the crossing
FRACTIONS = (1.0, 0.3, 0.1, 0.03)  # of the shipped yaw damping, tried in turn
RELATIVE_STEP = 1e-2  # central differences at c (1 +- this)


def coach():
    """``(scenario, vehicle, params, track, model)`` of the coach on straight track, the
    contact table."""
    scenario = parse_scenario(SCENARIO, "coach-straight")
    vehicle, params, track = scenario.build()
    return scenario, vehicle, params, track, contact_model("table", vehicle, params, track)


def linear(stability, params, points=8):
    """(critical SpeedPoint, root locus) of one parameter set."""
    import numpy as np

    locus = stability.sweep(np.linspace(*SPEEDS, points), params)
    return stability.critical_speed(*SPEEDS, params, points=locus), locus


def point_dict(p):
    return {"speed_m_s": p.speed, "speed_km_h": 3.6 * p.speed,
            "frequency_hz": p.frequency_hz, "damping_ratio": p.damping_ratio,
            "eigenvalue": [p.eigenvalue.real, p.eigenvalue.imag]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--nonlinear", help="also the nonlinear critical speed in LO:HI m/s")
    parser.add_argument("--out", default=str(Path(__file__).with_name("results.json")))
    args = parser.parse_args()
    start = time.perf_counter()
    scenario, vehicle, params, track, model = coach()
    stability = LinearStability(vehicle, params, track, model)
    out = {"experiment": "coach_stability", "load_before": os.getloadavg()}
    c0 = float(get_values(vehicle, params, [YAW])[0])
    out["yaw_damping_N_s_m"] = c0

    without = set_values(vehicle, params, [SERIES], [1.0])
    bare, locus = linear(stability, without)
    out["linear_without_yaw_dampers"] = point_dict(bare)
    out["root_locus_without"] = [point_dict(p) for p in locus]
    print(json.dumps(out["linear_without_yaw_dampers"]), file=sys.stderr)
    # with the shipped yaw dampers the hunting mode may stay damped over the whole range:
    # then the least damping found is reported, and the gradient is taken at the largest
    # fraction of the shipped damping (of FRACTIONS) whose coach does cross in the range
    crossing = None
    for fraction in FRACTIONS:
        trial = set_values(vehicle, params, [YAW], [fraction * c0])
        try:
            point, locus = linear(stability, trial)
        except ValueError as error:
            out.setdefault("no_crossing", []).append({"fraction": fraction,
                                                      "message": str(error)})
            print(str(error), file=sys.stderr)
            continue
        crossing = (fraction, trial, point)
        out[f"linear_with_yaw_dampers_at_{fraction:g}"] = point_dict(point)
        out[f"root_locus_with_at_{fraction:g}"] = [point_dict(p) for p in locus]
        print(json.dumps(point_dict(point)), file=sys.stderr)
        break
    fraction, at, point = crossing
    c = fraction * c0
    gradient = stability.critical_speed_gradient(point, [YAW], at)[YAW]
    h = RELATIVE_STEP * c
    sides = [linear(stability, set_values(vehicle, params, [YAW], [c + s]))[0].speed
             for s in (h, -h)]
    central = (sides[0] - sides[1]) / (2.0 * h)
    out["gradient"] = {"yaw_damping_N_s_m": c, "fraction_of_shipped": fraction,
                       "implicit_m_s_per_N_s_m": gradient,
                       "central_difference_m_s_per_N_s_m": central,
                       "relative_step": RELATIVE_STEP,
                       "relative_difference": abs(gradient / central - 1.0)}
    print(json.dumps(out["gradient"]), file=sys.stderr)

    if args.nonlinear:
        low, high = speed_range(args.nonlinear, "--nonlinear")
        options = nonlinear_options(scenario)
        for label, p in (("with", params), ("without", without)):  # noqa: B007
            out[f"nonlinear_{label}_yaw_dampers"] = nonlinear_study(
                vehicle, p, track, low, high, rate=5.0 / 3.6, resolution=1.0,
                options=options, model=model,
                progress=lambda line: print(line, file=sys.stderr))
    out["wall_s"] = time.perf_counter() - start
    out["load_after"] = os.getloadavg()
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
