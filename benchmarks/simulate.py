"""Benchmark of a full simulation: the 11-body trailer (S1002 on UIC60 1:40) on straight
track at 18.3 m/s with the paper's 2 mm initial misalignment.

Prints JSON per solver setting: compile time, wall time, simulated time, real-time
factor (simulated / wall), steps accepted and rejected, right-hand-side evaluations
(Tsit5: 6 per attempted step, first-same-as-last), and the load average.
Usage: ``python benchmarks/simulate.py [--duration 5] [--rtol 1e-4 1e-3]``.
"""

import argparse
import json
import os
import platform

import numpy as np

from jaxrail import enable_float64

enable_float64()

from jaxrail.simulation import SolverOptions, simulate  # noqa: E402
from jaxrail.track import straight_track  # noqa: E402
from jaxrail.vehicles import trailer  # noqa: E402

STAGES = 6  # Tsit5 evaluations per attempted step (FSAL: the 7th is the next step's 1st)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=5.0, help="simulated time [s]")
    parser.add_argument("--speed", type=float, default=18.3, help="[m/s]")
    parser.add_argument("--rtol", type=float, nargs="+", default=[1e-4, 1e-3])
    args = parser.parse_args()
    vehicle, params = trailer()
    track = straight_track(args.speed * args.duration + 60.0)
    runs = []
    load_before = os.getloadavg()
    for rtol in args.rtol:
        options = SolverOptions(rtol=rtol, atol=rtol * 1e-3, n_outputs=int(args.duration * 50) + 1)
        result = simulate(vehicle, params, track, args.duration, args.speed, 2e-3, options=options)
        steps = int(result.steps)
        runs.append({
            "rtol": rtol, "atol": rtol * 1e-3, "status": result.status,
            "compile_time_s": round(float(result.compile_time_s), 2),
            "wall_time_s": round(float(result.wall_time_s), 2),
            "simulated_time_s": result.simulated_time_s,
            "real_time_factor": round(result.simulated_time_s / float(result.wall_time_s), 4),
            "steps_accepted": int(result.accepted_steps),
            "steps_rejected": int(result.rejected_steps),
            "rhs_evaluations": STAGES * steps + 1,
            "wall_ms_per_rhs": round(1e3 * float(result.wall_time_s) / (STAGES * steps + 1), 3),
            "max_constraint_violation_m": float(np.nanmax(result.constraint_violation)),
            "final_lateral_mm": [round(1e3 * float(y), 4) for y in result.wheelset_lateral[-1]],
        })
    print(json.dumps({
        "benchmark": "simulate", "vehicle": "trailer (11 bodies, 8 wheels)",
        "track": "straight", "speed_m_s": args.speed, "misalignment_m": 2e-3,
        "solver": "Tsit5 + PID", "runs": runs,
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                    "load_before": load_before, "load_after": os.getloadavg()},
    }, indent=2))


if __name__ == "__main__":
    main()
