"""Monte Carlo study: the bogie entering the paper's 300 m curve (shortened) over speed
10-25 m/s and initial misalignment 0-5 mm (docs/montecarlo.md).

``python experiments/montecarlo_speed_misalignment/run.py OUT [--samples 128]
[--chunk 64] [--seed 2026] [--host-devices 2]`` writes into OUT the table (CSV and
Parquet), the statistics (JSON) and the figures (maps over speed and misalignment,
distributions); each chunk is split over the host devices (one per core here).
"""

import argparse
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
    args = parser.parse_args()
    use_host_devices(args.host_devices)  # before anything starts JAX's devices
    enable_float64()
    from jaxrail.montecarlo import run_montecarlo, write_table
    from jaxrail.plots.montecarlo import QUANTITIES, plot_distributions, plot_maps
    from jaxrail.scenarios import load_scenario

    args.out.mkdir(parents=True, exist_ok=True)
    scenario = load_scenario(HERE / "bogie-curve.toml")
    start = time.perf_counter()
    mc = run_montecarlo(scenario, VARY, args.samples, seed=args.seed, chunk=args.chunk,
                        duration=args.duration, progress=True)
    wall = time.perf_counter() - start
    table = mc.table
    for suffix in (".csv", ".parquet"):
        write_table(args.out / f"table{suffix}", table)
    plot_maps(table, args.out / "maps.png")
    plot_distributions(table, args.out / "distributions.png")
    duration = scenario.duration if args.duration is None else args.duration
    ok = table["status"] == "successful"
    stats = {"scenario": str(HERE / "bogie-curve.toml"), "vary": VARY,
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
    (args.out / "stats.json").write_text(json.dumps(stats, indent=2) + "\n")
    print(json.dumps(stats, indent=2))


if __name__ == "__main__":
    main()
