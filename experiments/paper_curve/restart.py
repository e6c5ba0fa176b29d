"""Restart the real-profile run of the paper's curve from a kept state, to measure
whether the leading wheelset chatters in flange contact: restart the ``paper-curve`` run
kept by ``python benchmarks/paper_curve.py --save DIR`` at ``--start`` seconds (with
``jaxrail.vehicles.wheel_rail.MIN_CURVATURE_RATIO`` set to ``--floor`` if given), run
``--duration`` seconds with the code as it is, and print JSON: status, steps, the share
of output samples with the leading outer wheel unloaded, its largest normal force and
the standard deviation of the leading wheelset's lateral displacement.
Usage: ``python experiments/paper_curve/restart.py DIR [--floor 3.0]``.
"""

import argparse
import json
import pickle
from pathlib import Path

import numpy as np

from jaxrail import enable_float64

enable_float64()

import jaxrail.vehicles.wheel_rail as wheel_rail  # noqa: E402
from jaxrail.scenarios import load_scenario  # noqa: E402
from jaxrail.simulation import SolverOptions, simulate  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("directory", type=Path)
    parser.add_argument("--floor", type=float, default=None, help="B/A floor [-] (default: the library's)")
    parser.add_argument("--start", type=float, default=4.0, help="[s]")
    parser.add_argument("--duration", type=float, default=1.0, help="[s]")
    args = parser.parse_args()
    if args.floor is not None:
        wheel_rail.MIN_CURVATURE_RATIO = args.floor  # read when the right-hand side is traced
    scenario = load_scenario("paper-curve")
    vehicle, params, track = scenario.build()
    kept = pickle.loads((args.directory / "paper-curve.pkl").read_bytes())
    k = int(np.argmin(np.abs(np.asarray(kept.t) - args.start)))
    result = simulate(vehicle, params, track, args.duration, scenario.speed,
                      initial=(kept.q[k], kept.qdot[k]),
                      options=SolverOptions(n_outputs=int(args.duration * 200) + 1))
    wheels = result.wheels
    active = np.asarray(wheels.active)[:, 0, 1]  # leading wheelset, right (outer) wheel
    normal = np.where(active, np.asarray(wheels.normal_force)[:, 0, 1], 0.0).sum(axis=1)
    print(json.dumps({
        "floor": wheel_rail.MIN_CURVATURE_RATIO, "start_s": float(kept.t[k]), "duration_s": args.duration,
        "status": result.status, "steps_accepted": int(result.accepted_steps),
        "steps_rejected": int(result.rejected_steps),
        "outer_wheel_unloaded_share": float(np.mean(~active.any(axis=1))),
        "outer_wheel_max_normal_force_N": float(normal.max()),
        "leading_lateral_std_m": float(np.std(np.asarray(result.wheelset_lateral)[:, 0])),
    }, indent=2))


if __name__ == "__main__":
    main()
