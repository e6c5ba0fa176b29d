"""Throughput of one vmapped Monte Carlo batch as the batch grows, on JAX's default
device (a GPU where there is one; docs/montecarlo.md, "On a GPU").

``python benchmarks/montecarlo_batch_size.py [--samples 256 1024 4096] [--duration
0.25] [--contact table|online] [--loop 2] [--budget 420] [--out FILE]`` runs the study
of ``benchmarks/montecarlo.py`` (``bogie-curve-entry``, speeds 80-120 % of the
scenario's, misalignments 0-4 mm) as one batch per sample count, each a single chunk
on the first device, and prints JSON: the device, jax's version, the load, and per
count the compile and run times [s], samples and simulated seconds per wall second,
the run time per member and step [us] (the initial equilibrium included), the statuses,
and the first members' wheelset lateral displacements [m] (to compare devices).
``--loop N`` then runs the first N samples of the smallest count one after another
(the unbatched program compiled once) and reports the largest difference between
their displacements and the batch's members' [m]. A count that would end past
``--budget`` seconds is skipped and says so; one that fails records its error and the
next one runs. ``--out`` rewrites the JSON there, whole, after each count, so that a
run cut short keeps what it measured.
"""

import argparse
import json
import os
import sys
import time
import traceback

from montecarlo import one_after_another, study_inputs

from jaxrail._files import write_text

FIRST_MEMBERS = 8  # members whose displacements the JSON keeps


def write_whole(path, report):
    """``report`` as JSON to ``path`` (if given), replacing it whole or not at all."""
    if path is not None:
        write_text(path, json.dumps(report, indent=1))


def versions():
    import jax
    import jaxlib

    device = jax.devices()[0]
    return {"jax": jax.__version__, "jaxlib": jaxlib.__version__,
            "platform": device.platform, "device_kind": device.device_kind,
            "devices": len(jax.devices()), "cores": os.cpu_count(),
            "load_start": os.getloadavg()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenario", default="bogie-curve-entry")
    parser.add_argument("--samples", type=int, nargs="+", default=[256, 1024, 4096])
    parser.add_argument("--duration", type=float, default=0.25, help="[s] per sample")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--contact", choices=("online", "table"), default="table")
    parser.add_argument("--loop", type=int, default=2,
                        help="samples run one after another first (0: none)")
    parser.add_argument("--budget", type=float, default=float("inf"),
                        help="[s] skip a count whose estimated end lies past this")
    parser.add_argument("--out", default=None, help="JSON file rewritten after each count")
    args = parser.parse_args()
    started = time.perf_counter()

    import jax
    import numpy as np

    from jaxrail import enable_float64

    enable_float64()
    from jaxrail.montecarlo import run_samples
    from jaxrail.scenarios import load_scenario

    report = {"benchmark": "montecarlo_batch_size", "scenario": args.scenario,
              "contact": args.contact, "duration_s": args.duration, "seed": args.seed,
              **versions(), "loop": None, "batches": []}
    scenario = load_scenario(args.scenario)
    t0 = time.perf_counter()
    built = scenario.build()
    # the contact model built (in table mode the table, built or read) so that its cost
    # is reported apart; each run below reads the table again from the disk cache
    scenario.contact_model(*built, args.contact)
    report["build_s"] = time.perf_counter() - t0
    options = scenario.solver_options(duration=args.duration)
    steps = (round(args.duration / options.fixed_step) if options.fixed_step else None)
    report["steps_per_sample"] = steps
    sizes = sorted(args.samples)
    smallest, smallest_run_s = None, None  # the smallest batch's displacements, time
    last = None
    for n in sizes:
        elapsed = time.perf_counter() - started
        if last is not None:
            estimate = 1.5 * last["compile_s"] + 1.3 * last["run_s"] * n / last["samples"]
        else:
            estimate = 0.0
        if elapsed + estimate > args.budget:
            report["batches"].append({"samples": n, "skipped": f"budget: {elapsed:.0f} s "
                                      f"spent, about {estimate:.0f} s more needed"})
            continue
        try:
            drawn = study_inputs(scenario, n, args.seed)
            batch = run_samples(scenario, drawn, duration=args.duration, chunk=n,
                                built=built, keep_results=True, devices=jax.devices()[:1],
                                contact=args.contact)
            lateral = np.asarray(batch.results.wheelset_lateral)
            entry = {"samples": n, "compile_s": batch.compile_time_s,
                     "run_s": batch.run_time_s, "samples_per_s": n / batch.run_time_s,
                     "simulated_per_s": batch.throughput(args.duration),
                     "statuses": batch.statuses,
                     "first_lateral_m": lateral[:FIRST_MEMBERS].tolist(),
                     "load": os.getloadavg()}
            if steps:
                entry["member_time_per_step_us"] = 1e6 * batch.run_time_s / n / steps
            if smallest is None:
                smallest, smallest_run_s = lateral, batch.run_time_s
            last = entry
        except Exception:
            entry = {"samples": n, "error": traceback.format_exc()[-2000:]}
        report["batches"].append(entry)
        write_whole(args.out, report)
        print(json.dumps({k: v for k, v in entry.items() if k != "first_lateral_m"}),
              file=sys.stderr, flush=True)
    if args.loop and smallest is not None:
        elapsed = time.perf_counter() - started
        # a run alone takes at most as long as the smallest batch
        estimate = last["compile_s"] + smallest_run_s * args.loop
        if elapsed + estimate > args.budget:
            report["loop"] = {"skipped": f"budget: {elapsed:.0f} s spent, about "
                                         f"{estimate:.0f} s more needed"}
        else:
            try:
                drawn = study_inputs(scenario, sizes[0], args.seed)
                compile_s, run_s, lateral = one_after_another(
                    scenario, built, drawn, args.duration, args.contact, args.loop)
                report["loop"] = {
                    "samples": args.loop, "compile_s": compile_s, "run_s": run_s,
                    "samples_per_s": args.loop / run_s,
                    "simulated_per_s": args.loop * args.duration / run_s,
                    "max_difference_from_batch_m": float(
                        np.nanmax(np.abs(smallest[:args.loop] - lateral)))}
            except Exception:
                report["loop"] = {"error": traceback.format_exc()[-2000:]}
        print(json.dumps(report["loop"]), file=sys.stderr, flush=True)
    report["total_s"] = time.perf_counter() - started
    write_whole(args.out, report)
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
