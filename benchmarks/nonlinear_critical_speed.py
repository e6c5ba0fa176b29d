"""The nonlinear critical speed of a built-in scenario's vehicle on its straight track by
both methods (jaxrail.stability.nonlinear): ramp-down at a rate and at half of it, and
brute force; with the linear critical speed beside them. Prints JSON (the ramps'
amplitude against speed left out unless --curves).

    python benchmarks/nonlinear_critical_speed.py suspended-wheelset --speeds 65:95
    python benchmarks/nonlinear_critical_speed.py straight --speeds 50:110 --contact table
"""

import argparse
import json
import os
import time

import jax

jax.config.update("jax_enable_x64", True)

from jaxrail.scenarios import load_scenario  # noqa: E402
from jaxrail.simulation import SolverOptions  # noqa: E402
from jaxrail.stability import LinearStability  # noqa: E402
from jaxrail.stability.nonlinear import (DISTURBANCE, GENSYS_RATE, brute_force,  # noqa: E402
                                         ramp_down)
from jaxrail.stability.report import speed_range  # noqa: E402
from jaxrail.track import straight_track  # noqa: E402
from jaxrail.vehicles import contact_model  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario")
    parser.add_argument("--speeds", default="65:95", help="LO:HI [m/s]")
    parser.add_argument("--contact", choices=("online", "table"), default="online")
    parser.add_argument("--rate", type=float, default=GENSYS_RATE, help="ramp [m/s^2]")
    parser.add_argument("--hold", type=float, default=2.0, help="[s] at HI before the ramp")
    parser.add_argument("--disturbance", type=float, default=DISTURBANCE,
                        help="[m] lateral shift of the rest pose that excites the cycle")
    parser.add_argument("--duration", type=float, default=5.0, help="[s] brute-force runs")
    parser.add_argument("--resolution", type=float, default=0.5, help="[m/s] brute force")
    parser.add_argument("--skip", nargs="*", default=(), choices=("linear", "half", "brute"))
    parser.add_argument("--curves", action="store_true")
    args = parser.parse_args()
    low, high = speed_range(args.speeds)
    scenario = load_scenario(args.scenario)
    vehicle, params, built = scenario.build()
    length = 100.0 + high * (args.hold + (high - low) / (0.5 * args.rate))
    track = straight_track(length, rails=built.rails)
    model = contact_model(args.contact, vehicle, params, track, progress=True)
    options = SolverOptions(rtol=scenario.rtol, atol=scenario.atol, integrator="imex")
    out = {"scenario": args.scenario, "vehicle": vehicle.name, "contact": args.contact,
           "speeds_m_s": [low, high], "load_average_start": os.getloadavg()[0]}
    if "linear" not in args.skip:
        start = time.perf_counter()
        stability = LinearStability(vehicle, params, track, model)
        try:
            critical = stability.critical_speed(low, 1.6 * high)
            out["linear"] = {"critical_speed_m_s": critical.speed,
                             "frequency_hz": critical.frequency_hz}
        except ValueError as error:
            out["linear"] = {"error": str(error)}
        out["linear"]["time_s"] = time.perf_counter() - start
    ramps = {}
    for name, rate in (("ramp_down", args.rate), ("ramp_down_half_rate", 0.5 * args.rate)):
        if name == "ramp_down_half_rate" and "half" in args.skip:
            continue
        ramp = ramp_down(vehicle, params, track, high, low, rate=rate, hold=args.hold,
                         disturbance=args.disturbance, options=options,
                         contact_model=model)
        curve = ramp.pop("amplitude_against_speed")
        if args.curves:
            ramp["amplitude_against_speed"] = curve
        ramps[name] = out[name] = ramp
    if "brute" not in args.skip:
        out["brute_force"] = brute_force(
            vehicle, params, track, low, high, resolution=args.resolution,
            duration=args.duration, disturbance=args.disturbance, options=options,
            contact_model=model, progress=lambda line: print(line, flush=True))
    speeds = {k: v.get("critical_speed_m_s") for k, v in out.items()
              if isinstance(v, dict) and "critical_speed_m_s" in v}
    reference = speeds.get("ramp_down")
    if reference:
        out["relative_to_ramp_down"] = {k: (v / reference - 1.0 if v else None)
                                        for k, v in speeds.items() if k != "ramp_down"}
    out["load_average_end"] = os.getloadavg()[0]
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
