"""The gradient of wear through a run (docs/wear.md, "The gradient of wear"): the wear
per km of every wheel and the part on the flange, their derivatives in named parameters
by forward mode through the run, the elasticities, and central differences beside them.

``python benchmarks/wear_gradient.py [--scenario bogie-curve-entry] [--from 0.5]
[--names primary_longitudinal_stiffness friction wheelbase ...] [--step 1e-4]``
prints JSON: per parameter its value, d(total wear per km)/d(parameter) by forward mode
and by central differences (relative step ``--step``), the elasticity d ln V / d ln p,
the same for the flange wear; the times of the first call (compile and run) and of one
call; the load.
"""

import argparse
import json
import os
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

from jaxrail.scenarios import load_scenario  # noqa: E402
from jaxrail.wear import ArchardKTH, wear_gradient  # noqa: E402

NAMES = ("primary_longitudinal_stiffness", "primary_lateral_stiffness", "friction",
         "wheelbase")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="bogie-curve-entry")
    parser.add_argument("--from", dest="t_from", type=float, default=0.5)
    parser.add_argument("--names", nargs="+", default=list(NAMES))
    parser.add_argument("--step", type=float, default=1e-4)
    args = parser.parse_args()
    scenario = load_scenario(args.scenario)
    built = scenario.build()
    model = scenario.contact_model(*built)
    law = ArchardKTH()

    def at(values=None):
        return wear_gradient(scenario, args.names, law, t_from=args.t_from, built=built,
                             model=model, values=values)

    start = time.perf_counter()
    g = at()
    first_s = time.perf_counter() - start
    start = time.perf_counter()
    at()
    call_s = time.perf_counter() - start
    volume, flange = float(g.volume_per_km.sum()), float(g.flange_per_km.sum())
    rows = {}
    for i, name in enumerate(g.names):
        h = args.step * g.values[i]
        e = np.eye(len(g.names))[i] * h
        plus, minus = at(g.values + e), at(g.values - e)
        fd = (plus.volume_per_km.sum() - minus.volume_per_km.sum()) / (2 * h)
        fd_flange = (plus.flange_per_km.sum() - minus.flange_per_km.sum()) / (2 * h)
        d = float(g.d_volume_per_km[..., i].sum())
        d_flange = float(g.d_flange_per_km[..., i].sum())
        rows[name] = {"value": float(g.values[i]), "d_volume_per_km": d,
                      "d_volume_per_km_central_difference": float(fd),
                      "elasticity": d * float(g.values[i]) / volume,
                      "d_flange_per_km": d_flange,
                      "d_flange_per_km_central_difference": float(fd_flange),
                      "flange_elasticity": d_flange * float(g.values[i]) / flange
                      if flange > 0 else None}
    print(json.dumps({"scenario": scenario.name, "wear_from_s": args.t_from,
                      "volume_per_km_mm3": volume, "flange_per_km_mm3": flange,
                      "per_wheel_volume_per_km_mm3": g.volume_per_km.tolist(),
                      "parameters": rows, "first_call_s": first_s, "call_s": call_s,
                      "load": os.getloadavg()}, indent=2))


if __name__ == "__main__":
    main()
