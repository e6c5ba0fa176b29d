"""Explicit against implicit integration of the trailer or of a single free wheelset
(S1002 on UIC60 1:40, straight track, 18.3 m/s, 2 mm misalignment): the measurement
behind the default solver.

For each diffrax solver, one run of ``--duration`` seconds with the PID controller at
``--rtol`` (atol = rtol / 1000). Prints JSON: compile time, wall time, steps accepted
and rejected, and the wheelsets' final lateral displacement (to compare accuracy).
Usage: ``python benchmarks/solvers.py [--vehicle trailer|single-wheelset]
[--duration 0.2] [--rtol 1e-4] [--solvers Tsit5 Dopri5 Bosh3 Kvaerno3 Kvaerno5]``.
"""

import argparse
import json
import os

import diffrax

from jaxrail import enable_float64

enable_float64()

from jaxrail.simulation import SolverOptions, simulate  # noqa: E402
from jaxrail.track import straight_track  # noqa: E402
from jaxrail.profiles import s1002  # noqa: E402
from jaxrail.vehicles import single_wheelset, trailer  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=0.2, help="[s]")
    parser.add_argument("--rtol", type=float, default=1e-4)
    parser.add_argument("--solvers", nargs="+",
                        default=["Tsit5", "Dopri5", "Bosh3", "Kvaerno3", "Kvaerno5"])
    parser.add_argument("--vehicle", choices=("trailer", "single-wheelset"), default="trailer")
    args = parser.parse_args()
    vehicle, params = (trailer() if args.vehicle == "trailer"
                       else single_wheelset(s1002()))
    track = straight_track(100.0)
    options = SolverOptions(rtol=args.rtol, atol=args.rtol * 1e-3, n_outputs=3)
    runs = []
    for name in args.solvers:
        result = simulate(vehicle, params, track, args.duration, 18.3, 2e-3, options=options,
                          solver=getattr(diffrax, name)())
        runs.append({
            "solver": name, "implicit": name.startswith("Kvaerno"), "status": result.status,
            "compile_time_s": round(float(result.compile_time_s), 1),
            "wall_time_s": round(float(result.wall_time_s), 2),
            "steps_accepted": int(result.accepted_steps),
            "steps_rejected": int(result.rejected_steps),
            "final_lateral_mm": [round(1e3 * float(y), 5) for y in result.wheelset_lateral[-1]],
        })
        print(json.dumps(runs[-1]), flush=True)
    print(json.dumps({"benchmark": "solvers", "vehicle": args.vehicle,
                      "duration_s": args.duration, "rtol": args.rtol,
                      "runs": runs, "load": os.getloadavg()}, indent=2))


if __name__ == "__main__":
    main()
