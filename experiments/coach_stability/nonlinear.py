"""The complete coach's nonlinear critical speed with and without its yaw dampers, by the
ramp-down and by brute force (jaxrail.stability.nonlinear), on ideal straight track,
S1002 on UIC60 1:40, friction 0.4, the contact table, IMEX.

The ramp falls at ``--rate`` (default four times GENSYS's 5 km/h per second, so that
the run from above the linear critical speed stays short; the ramp-down then reads up
to rate * window / 2 = 1.4 m/s low, and brute force refines it to ``--resolution``).
"Without yaw dampers" sets their series stiffness to 1 N/m, as `run.py` does.
``--ramp-only`` runs the ramp-down alone (brute force costs several constant-speed runs
of 5 s per batch, over an hour per case on this 2-core machine when it is shared).

Writes ``nonlinear.json`` beside this file (``--out``).
Usage: ``python experiments/coach_stability/nonlinear.py [--with LO:HI] [--without LO:HI]
[--rate M_S2] [--resolution M_S] [--ramp-only] [--out FILE]``.
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path

import jaxrail

jaxrail.enable_float64()

from jaxrail.stability.nonlinear import GENSYS_RATE, ramp_down  # noqa: E402
from jaxrail.stability.report import (nonlinear_options, nonlinear_study,  # noqa: E402
                                      ramp_track, speed_range)
from jaxrail.vehicles import set_values  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from run import SERIES, coach  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--with", dest="with_", default="120:190",
                        help="speed range [m/s] with the yaw dampers")
    parser.add_argument("--without", default="70:120",
                        help="speed range [m/s] without them")
    parser.add_argument("--rate", type=float, default=4.0 * GENSYS_RATE)
    parser.add_argument("--resolution", type=float, default=2.0)
    parser.add_argument("--only", choices=("with", "without"))
    parser.add_argument("--ramp-only", action="store_true")
    parser.add_argument("--out", default=str(Path(__file__).with_name("nonlinear.json")))
    args = parser.parse_args()
    start = time.perf_counter()
    scenario, vehicle, params, track, model = coach()
    options = nonlinear_options(scenario)
    out = {"experiment": "coach_stability nonlinear", "load_before": os.getloadavg(),
           "rate_m_s2": args.rate, "resolution_m_s": args.resolution}
    cases = {"with": (params, args.with_),
             "without": (set_values(vehicle, params, [SERIES], [1.0]), args.without)}
    for label, (p, limits) in cases.items():
        if args.only and label != args.only:
            continue
        low, high = speed_range(limits, f"--{label}")
        began = time.perf_counter()
        if args.ramp_only:  # the straight nonlinear_study runs the ramp on
            hold = 2.0
            ramp = ramp_down(vehicle, p, ramp_track(track, low, high, args.rate, hold), high,
                             low, rate=args.rate, hold=hold, options=options,
                             contact_model=model)
            study = {"ramp_down_critical_speed_m_s": ramp["critical_speed_m_s"],
                     "nonlinear_critical_speed_m_s": None, "ramp_down": ramp}
        else:
            study = nonlinear_study(vehicle, p, track, low, high, rate=args.rate,
                                    resolution=args.resolution, options=options, model=model,
                                    progress=lambda line: print(line, file=sys.stderr,
                                                                flush=True))
        study["wall_s"] = time.perf_counter() - began
        study["range_m_s"] = [low, high]
        out[f"{label}_yaw_dampers"] = study
        print(label, study["nonlinear_critical_speed_m_s"], study["ramp_down_critical_speed_m_s"],
              file=sys.stderr, flush=True)
        out["wall_s"] = time.perf_counter() - start
        out["load_after"] = os.getloadavg()
        Path(args.out).write_text(json.dumps(out, indent=1, default=str) + "\n")


if __name__ == "__main__":
    main()
