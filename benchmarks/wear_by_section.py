"""The wear of each section of a route on the new profile (docs/wear.md, "What limits
the step"): every wheel's wear per km and its flange part, and the largest height the
evolution's update would take off per km (the mean over the wheels, smoothed as
:func:`jaxrail.wear.evolution.update_per_km`), section by section, and the 200 000 km
such a rate would add up to.

``python benchmarks/wear_by_section.py [ROUTE] [--law usfd] [--contact table]``
(default the route ``benchmarks/routes/radii.toml``; ``--law`` replaces the route's
wear model) prints JSON, with the times and the load.
"""

import argparse
import dataclasses
import json
import os
import time
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

from jaxrail.wear.evolution import route_wear, update_per_km  # noqa: E402
from jaxrail.wear.laws import MODELS  # noqa: E402
from jaxrail.wear.route import load_route  # noqa: E402

DEFAULT_ROUTE = Path(__file__).parent / "routes" / "radii.toml"


def section_label(section) -> str:
    kind = "straight" if not section.curved else \
        f"{section.radius:g} m {section.direction}, {1e3 * section.cant:g} mm"
    return f"{kind}, {section.speed:g} m/s"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("route", nargs="?", default=str(DEFAULT_ROUTE))
    parser.add_argument("--law", choices=MODELS, help="the wear model (default the route's)")
    parser.add_argument("--contact", default="table", choices=("table", "online"))
    args = parser.parse_args()
    route = load_route(args.route)
    if args.law is not None:
        route = dataclasses.replace(route, wear_model=args.law, wear={})
    start = time.perf_counter()
    wear = route_wear(route, contact=args.contact)
    wall = time.perf_counter() - start
    sections = []
    for k, section in enumerate(route.sections):
        update = update_per_km(wear.wheel_nodes, wear.sections_depth_per_km[k])
        peak = int(np.argmax(update))
        sections.append({
            "section": section_label(section),
            "completed": bool(wear.completed[k]),
            "volume_per_km_mm3": np.round(wear.sections_volume_per_km[k], 2).tolist(),
            "flange_per_km_mm3": np.round(wear.sections_flange_per_km[k], 2).tolist(),
            "update_peak_um_per_km": float(1e6 * update[peak]),
            "update_peak_y_mm": float(1e3 * wear.wheel_nodes[peak]),
            "update_peak_over_200000_km_mm": float(1e3 * update[peak] * 2e5)})
    print(json.dumps({"route": route.name, "wear_model": route.wear_model,
                      "contact": args.contact, "duration_s": route.duration,
                      "sections": sections,
                      "extrapolated_fraction": wear.extrapolated_fraction,
                      "compile_s": wear.compile_s, "run_s": wear.run_s, "wall_s": wall,
                      "load": os.getloadavg()}, indent=1))


if __name__ == "__main__":
    main()
