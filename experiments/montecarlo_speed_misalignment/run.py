"""Monte Carlo study: the bogie entering the paper's 300 m curve (shortened) over speed
10-25 m/s and initial misalignment 0-5 mm (docs/montecarlo.md), on the ideal track or,
with ``--irregularities SPECTRUM``, on realisations of that spectrum (3-150 m), the
realisation's seed drawn as a third input; with ``--flexible`` on the co-moving
flexible track (``bogie-curve-flexible.toml``) instead of rigid rails.

``python experiments/montecarlo_speed_misalignment/run.py OUT [--samples 128]
[--chunk 64] [--seed 2026] [--host-devices 2] [--irregularities german-low]
[--flexible [--rigid-rails]] [--contact table]`` writes
into OUT the table (CSV and Parquet), the statistics (JSON) and the figures (maps over
speed and misalignment, distributions); each chunk is split over the host devices (one
per core here). Finished chunks are kept in OUT/table.chunks.json: the same command
resumes an interrupted study.
"""

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from jaxrail import enable_float64, use_host_devices

HERE = Path(__file__).parent
VARY = ("speed=10:25", "misalignment=0:5e-3")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--samples", type=int, default=128)
    parser.add_argument("--chunk", type=int, default=64)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--duration", type=float, help="[s] (default: the scenario's 1.5 s)")
    parser.add_argument("--host-devices", type=int, default=2)
    parser.add_argument("--irregularities", help="an irregularity spectrum, e.g. german-low")
    parser.add_argument("--flexible", action="store_true",
                        help="on the co-moving flexible track (bogie-curve-flexible.toml)")
    parser.add_argument("--rigid-rails", action="store_true",
                        help="with --flexible: the same scenario and solver on rigid rails "
                             "(the flexible study's comparison)")
    parser.add_argument("--contact", choices=("online", "table"),
                        help="the contact model (default: the scenario's, the search)")
    args = parser.parse_args()
    if args.rigid_rails and not args.flexible:
        parser.error("--rigid-rails goes with --flexible")
    use_host_devices(args.host_devices)  # before anything starts JAX's devices
    enable_float64()
    from jaxrail.montecarlo import run_montecarlo, write_table
    from jaxrail.plots.montecarlo import QUANTITIES, plot_distributions, plot_maps
    from jaxrail.scenarios import load_scenario
    from jaxrail.scenarios.irregularities import IrregularitySpec

    args.out.mkdir(parents=True, exist_ok=True)
    path = HERE / ("bogie-curve-flexible.toml" if args.flexible else "bogie-curve.toml")
    scenario = load_scenario(path)
    if args.rigid_rails:
        scenario = dataclasses.replace(scenario, flexible=None)
    if args.contact:
        scenario = dataclasses.replace(scenario, contact=args.contact)
    vary = VARY
    if args.irregularities:
        scenario = dataclasses.replace(scenario, irregularities=IrregularitySpec(
            "spectrum", spectrum=args.irregularities))
        vary = VARY + ("irregularity_seed=0:1000000",)
    start = time.perf_counter()
    checkpoint = args.out / "table.chunks.json"
    mc = run_montecarlo(scenario, vary, args.samples, seed=args.seed, chunk=args.chunk,
                        duration=args.duration, progress=True, checkpoint=checkpoint)
    wall = time.perf_counter() - start
    table = mc.table
    for suffix in (".csv", ".parquet"):
        write_table(args.out / f"table{suffix}", table)
    checkpoint.unlink(missing_ok=True)
    plot_maps(table, args.out / "maps.png")
    plot_distributions(table, args.out / "distributions.png")
    duration = scenario.duration if args.duration is None else args.duration
    ok = table["status"] == "successful"
    stats = {"scenario": str(path), "vary": vary,
             "irregularities": args.irregularities, "contact": scenario.contact,
             "support": "rigid" if scenario.flexible is None else "flexible",
             "samples": args.samples, "seed": args.seed, "duration_s": duration,
             "statuses": mc.statuses, "chunk": mc.chunk, "devices": mc.devices,
             "compile_time_s": mc.compile_time_s, "run_time_s": mc.run_time_s,
             "wall_time_s": wall, "throughput_simulated_s_per_s": mc.throughput(duration),
             "quantities": {}}
    for key, (title, unit, value) in QUANTITIES.items():
        z = value(table)[ok]
        z = z[np.isfinite(z)]
        stats["quantities"][key] = {"unit": unit, "min": float(z.min()),
                                    "median": float(np.median(z)), "max": float(z.max())}
        # how the quantity follows each input (rank correlation)
        for name in ("speed", "misalignment"):
            x = np.asarray(table[name])[ok][np.isfinite(value(table)[ok])]
            rx, rz = np.argsort(np.argsort(x)), np.argsort(np.argsort(z))
            stats["quantities"][key][f"spearman_{name}"] = float(np.corrcoef(rx, rz)[0, 1])
        # the share of the scatter the speed does not explain: 1 - R^2 of a quadratic
        # in the speed (what the misalignment and the track's realisation leave)
        x = np.asarray(table["speed"])[ok][np.isfinite(value(table)[ok])]
        fit = np.polyval(np.polyfit(x, z, 2), x)
        stats["quantities"][key]["variance_share_not_speed"] = float(
            np.var(z - fit) / np.var(z)) if np.var(z) > 0 else 0.0
    (args.out / "stats.json").write_text(json.dumps(stats, indent=2) + "\n")
    print(json.dumps(stats, indent=2))


if __name__ == "__main__":
    main()
