"""Benchmark of the paper's example: the trailer through the 300 m left curve at 18.3 m/s
for 41 s, with the simplified and the real S1002 profiles (built-in scenarios
``paper-curve-simplified`` and ``paper-curve``).

Prints JSON per profile kind: compile time, wall time, simulated time, real-time
factor, steps accepted and rejected, right-hand-side evaluations (Tsit5: 6 per attempted
step), status. With ``--save DIR`` it also keeps each run (``DIR/<scenario>.pkl``, the
SimulationResult as numpy arrays, for experiments/paper_curve/figures.py), its results
file (``.h5``) and summary (``.json``).
Usage: ``python benchmarks/paper_curve.py [--duration 41] [--save DIR]
[--scenarios paper-curve-simplified paper-curve]``.
"""

import argparse
import json
import os
import pickle
import platform
from pathlib import Path

import jax
import numpy as np

from jaxrail import enable_float64

enable_float64()

from jaxrail._files import write_atomically  # noqa: E402
from jaxrail.scenarios import load_scenario, run_scenario  # noqa: E402

STAGES = 6


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=None, help="[s] (default 41)")
    parser.add_argument("--save", type=Path, default=None, help="keep the runs in DIR")
    parser.add_argument("--scenarios", nargs="+",
                        default=["paper-curve-simplified", "paper-curve"])
    parser.add_argument("--progress", action="store_true")
    args = parser.parse_args()
    runs = []
    for name in args.scenarios:
        scenario = load_scenario(name)
        result, vehicle, params, _ = run_scenario(scenario, args.duration, args.progress)
        steps = int(result.steps)
        wall = float(result.wall_time_s)
        runs.append({
            "scenario": name, "wheel": scenario.wheel, "status": result.status,
            "compile_time_s": round(float(result.compile_time_s), 1),
            "wall_time_s": round(wall, 1), "simulated_time_s": result.simulated_time_s,
            "real_time_factor": round(result.simulated_time_s / wall, 4),
            "steps_accepted": int(result.accepted_steps),
            "steps_rejected": int(result.rejected_steps),
            "rhs_evaluations": STAGES * steps + 1,
            "max_constraint_violation_m": float(np.nanmax(result.constraint_violation)),
            "any_nan_in_valid_outputs": bool(np.any(np.isnan(
                np.asarray(result.wheelset_lateral)[np.asarray(result.valid)]))),
        })
        print(json.dumps(runs[-1]), flush=True)
        if args.save is not None:
            _save(args.save, name, scenario, result, vehicle, params)
    print(json.dumps({"benchmark": "paper_curve", "runs": runs,
                      "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                                  "load": os.getloadavg()}}, indent=2))


def _save(directory, name, scenario, result, vehicle, params):
    from jaxrail import __version__
    from jaxrail.results import summarize, write_results

    directory.mkdir(parents=True, exist_ok=True)
    host = jax.tree.map(np.asarray, result)
    write_atomically(directory / f"{name}.pkl",
                     lambda path: Path(path).write_bytes(pickle.dumps(host)))
    write_results(directory / f"{name}.h5", result, metadata={
        "scenario": name, "description": scenario.description,
        "jaxrail_version": __version__, "body_names": list(vehicle.system.body_names)})
    summary = summarize(result, friction=float(params.contact.friction))
    write_atomically(directory / f"{name}.json",
                     lambda path: Path(path).write_text(json.dumps(summary, indent=2)))


if __name__ == "__main__":
    main()
