"""Identification of the complete coach's yaw damping from a synthetic run.

The coach (`jaxrail/vehicles/data/coach.toml`) runs the first ``--duration`` seconds of
the built-in scenario `coach-curve-irregular` (straight, then the transition into a
1200 m curve, German low-level irregularities, 40 m/s, the contact table). Noise-free
measurements at 100 Hz of four channels (leading wheelset's lateral displacement and
yaw, the leading wheel's lateral force, the leading bogie's lateral acceleration) are
simulated with the shipped yaw damping; the fit starts ``--offset`` (relative) away
from it and finds it again by L-BFGS with the gradient through the whole run (forward
mode), closing with Gauss-Newton steps (jaxrail.identification).

Writes ``results.json`` beside this file (``--out``).
Usage: ``python experiments/coach_identify/run.py [--duration S] [--offset F] [--out FILE]``.
"""

import argparse
import dataclasses
import json
import os
import time
from pathlib import Path

import jax
import numpy as np

import jaxrail

jaxrail.enable_float64()

from jaxrail.identification import (Measurements, get_values, identify,  # noqa: E402
                                    simulate_channels)
from jaxrail.scenarios import load_scenario  # noqa: E402
from jaxrail.vehicles import contact_model  # noqa: E402

SCENARIO = "coach-curve-irregular"
NAME = "yaw_damper.damping"
CHANNELS = {  # channel: the noise standard deviation that weighs it in the fit
    "wheelset_lateral_1": 1e-4,  # [m]
    "wheelset_yaw_1": 1e-4,  # [rad]
    "wheel_lateral_force_1_right": 2e3,  # [N]
    "lateral_acceleration_bogie_1": 0.05,  # [m/s^2]
}
SAMPLE_RATE = 100.0  # [Hz]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=1.5)
    parser.add_argument("--offset", type=float, default=0.3)
    parser.add_argument("--out", default=str(Path(__file__).with_name("results.json")))
    args = parser.parse_args()
    start = time.perf_counter()
    scenario = dataclasses.replace(load_scenario(SCENARIO), duration=args.duration)
    vehicle, params, track = scenario.build()
    model = contact_model("table", vehicle, params, track, progress=True)
    truth = float(get_values(vehicle, params, [NAME])[0])
    times = np.linspace(0.0, args.duration, int(round(args.duration * SAMPLE_RATE)) + 1)
    values = np.asarray(jax.jit(lambda p: simulate_channels(
        vehicle, p, track, tuple(CHANNELS), times, speed=scenario.speed,
        misalignment=scenario.misalignment, duration=args.duration,
        options=scenario.solver_options(), contact_model=model))(params))
    measured = Measurements(times, tuple(CHANNELS), values, np.array(list(CHANNELS.values())))
    truth_s = time.perf_counter() - start
    result = identify(scenario, measured, [NAME], initial={NAME: truth * (1 + args.offset)},
                      max_iterations=30, progress=True, built=(vehicle, params, track),
                      contact="table")
    summary = result.as_dict()
    fitted = float(result.fit.values[0])
    out = {"experiment": "coach_identify", "scenario": SCENARIO, "duration_s": args.duration,
           "parameter": NAME, "truth": truth, "initial": truth * (1 + args.offset),
           "fitted": fitted, "relative_error": fitted / truth - 1.0,
           "channels": CHANNELS, "sample_rate_hz": SAMPLE_RATE,
           "truth_simulation_s": truth_s, "wall_s": time.perf_counter() - start,
           "load_after": os.getloadavg(), "identification": summary}
    Path(args.out).write_text(json.dumps(out, indent=1, default=str) + "\n")
    print(json.dumps({k: out[k] for k in ("truth", "initial", "fitted", "relative_error",
                                          "wall_s")}, indent=1))


if __name__ == "__main__":
    main()
