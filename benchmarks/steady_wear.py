"""The design sensitivity of wear (docs/wear.md, "The gradient of wear"): each wheel's
wear per km in the steady curving state of a scenario's vehicle on one arc, and its
derivatives in named parameters by the implicit function theorem
(:func:`jaxrail.wear.steady.steady_wear`), with central differences of the steady state
beside them.

``python benchmarks/steady_wear.py [--scenario paper-curve] [--radius 500] [--cant 0.12]
[--speed 20] [--contact table] [--law archard-kth] [--step 1e-3] [--names ...]`` prints
JSON: the wear per km of every wheel, per parameter its value, the derivative of the
vehicle's total wear per km, its elasticity d ln V / d ln p, the central difference,
and the times; the load.
"""

import argparse
import json
import os
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

from jaxrail.scenarios import load_scenario  # noqa: E402
from jaxrail.track import Arc, Track  # noqa: E402
from jaxrail.vehicles.parameters import get_values, set_values  # noqa: E402
from jaxrail.wear import wear_law  # noqa: E402
from jaxrail.wear.laws import MODELS  # noqa: E402
from jaxrail.wear.steady import steady_wear  # noqa: E402

NAMES = ("primary_longitudinal_stiffness", "primary_lateral_stiffness", "friction",
         "wheelbase")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="paper-curve")
    parser.add_argument("--radius", type=float, default=500.0)
    parser.add_argument("--cant", type=float, default=0.12)
    parser.add_argument("--speed", type=float, default=20.0)
    parser.add_argument("--contact", default="table")
    parser.add_argument("--law", default="archard-kth", choices=MODELS)
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--names", nargs="+", default=list(NAMES))
    args = parser.parse_args()
    scenario = load_scenario(args.scenario)
    vehicle, params, _ = scenario.build()
    track = Track.from_segments([Arc(400.0, args.radius, "left", args.cant)],
                                rails=scenario.rails())
    model = scenario.contact_model(vehicle, params, track, args.contact)
    wear = steady_wear(vehicle, params, track, wear_law(args.law), args.names, model)
    start = time.perf_counter()
    point = wear(args.speed)
    first_s = time.perf_counter() - start
    total = float(np.sum(point.wear_number_n))
    values = np.asarray(get_values(vehicle, params, tuple(args.names)))
    rows = {}
    for i, name in enumerate(args.names):
        d = float(np.sum(point.gradient[name]))
        h = args.step * values[i]

        def at(value):
            changed = set_values(vehicle, params, (name,), np.array([value]))
            return float(np.sum(wear(args.speed, changed, start=point.state).wear_number_n))
        fd = (at(values[i] + h) - at(values[i] - h)) / (2.0 * h)
        rows[name] = {"value": float(values[i]), "d_volume_per_km": d,
                      "d_volume_per_km_central_difference": fd,
                      "elasticity": d * float(values[i]) / total}
    print(json.dumps({"scenario": scenario.name, "radius_m": args.radius, "cant_m": args.cant,
                      "speed_m_s": args.speed, "contact": args.contact, "law": args.law,
                      "volume_per_km_mm3": np.asarray(point.wear_number_n).tolist(),
                      "total_volume_per_km_mm3": total, "parameters": rows,
                      "first_call_s": first_s, "load": os.getloadavg()}, indent=2))


if __name__ == "__main__":
    main()
