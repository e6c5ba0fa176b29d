"""The 11-body trailer on straight track with the paper's 2 mm initial misalignment.

Prints JSON (status, simulated and wall time, steps, maximum constraint violation,
whether any output is NaN, the wheelsets' lateral displacement at a few times) and
saves docs/figures/trailer_straight.png (lateral displacements and wheel loads).
Usage: ``python experiments/trailer_straight/run.py [--duration 10] [--speed 18.3]``.
"""

import argparse
import json
from pathlib import Path

import jax
import numpy as np

from jaxrail import enable_float64

enable_float64()

from jaxrail.plots.simulation import plot_wheelsets  # noqa: E402
from jaxrail.simulation import SolverOptions, simulate  # noqa: E402
from jaxrail.track import straight_track  # noqa: E402
from jaxrail.vehicles import trailer  # noqa: E402

FIGURE = Path(__file__).resolve().parents[2] / "docs" / "figures" / "trailer_straight.png"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=10.0, help="[s]")
    parser.add_argument("--speed", type=float, default=18.3, help="[m/s]")
    parser.add_argument("--misalignment", type=float, default=2e-3, help="[m]")
    parser.add_argument("--figure", type=Path, default=FIGURE)
    args = parser.parse_args()
    vehicle, params = trailer()
    track = straight_track(args.speed * args.duration + 60.0)
    options = SolverOptions(n_outputs=int(args.duration * 100) + 1, progress=True)
    result = simulate(vehicle, params, track, args.duration, args.speed, args.misalignment,
                      options=options)
    leaves = jax.tree.leaves((result.q, result.qdot, result.wheels))
    lateral = np.asarray(result.wheelset_lateral)
    every = max(1, (len(lateral) - 1) // 10)
    print(json.dumps({
        "status": result.status, "simulated_time_s": result.simulated_time_s,
        "compile_time_s": round(float(result.compile_time_s), 1),
        "wall_time_s": round(float(result.wall_time_s), 1),
        "steps_accepted": int(result.accepted_steps),
        "steps_rejected": int(result.rejected_steps),
        "max_constraint_violation_m": float(np.nanmax(result.constraint_violation)),
        "any_nan": bool(any(np.any(np.isnan(np.asarray(x, dtype=float))) for x in leaves)),
        "max_abs_lateral_mm_after_2s": float(1e3 * np.max(np.abs(
            lateral[np.asarray(result.t) >= 2.0]))),
        "lateral_mm": {f"{float(t):.1f}": [round(1e3 * float(y), 4) for y in row]
                       for t, row in zip(np.asarray(result.t)[::every], lateral[::every])},
    }, indent=2))
    plot_wheelsets(result, args.figure, "trailer on straight track, 18.3 m/s, 2 mm misalignment")


if __name__ == "__main__":
    main()
