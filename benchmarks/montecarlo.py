"""Throughput of a vmapped Monte Carlo batch against the same runs one after another,
on 1 and 2 host devices (docs/montecarlo.md).

``python benchmarks/montecarlo.py [--samples 64] [--duration 0.25] [--scenario S]
[--contact online|table]`` prints JSON: per device count, the compile and run times [s] of the batch (one
compiled call of all samples, sharded over the devices) and of the sequential loop
(the unbatched simulation compiled once, then called per sample), the throughputs in
simulated seconds per wall second, their ratio, and the largest difference between
the two runs' wheelset lateral displacements [m]. Each configuration runs in a child
process started as it would be used: the sequential loop and the 1-device batch with
the environment as given (XLA's defaults), the 2-device batch with two host devices
that run side by side (:func:`jaxrail.use_host_devices`; XLA reads its flags once, at
start).
"""

import argparse
import json
import os
import subprocess
import sys
import time

from jaxrail._devices import host_device_environment


def study_inputs(scenario, samples, seed):
    """The benchmarks' study: ``samples`` speeds at 80-120 % of the scenario's and
    misalignments 0-4 mm, a Latin hypercube drawn with ``seed``."""
    from jaxrail.montecarlo import draw, parse_variation

    return draw([parse_variation(f"speed={0.8 * scenario.speed}:{1.2 * scenario.speed}"),
                 parse_variation("misalignment=0:4e-3")], samples, seed=seed)


def one_after_another(scenario, built, drawn, duration, contact, count=None):
    """The first ``count`` (default all) samples of ``drawn``, one after another with the
    unbatched ``solve`` compiled once: (compile [s], run [s], wheelset lateral
    displacements (count, outputs, wheelsets) [m])."""
    import jax
    import numpy as np

    from jaxrail.simulation import solve

    vehicle, params, track = built
    options = scenario.solver_options(duration=duration)
    model = scenario.contact_model(vehicle, params, track, contact)
    one = jax.jit(lambda v, m: solve(vehicle, params, track, duration, v, m,
                                     options=options, contact_model=model))
    start = time.perf_counter()
    one = one.lower(drawn["speed"][0], drawn["misalignment"][0]).compile()
    compile_s = time.perf_counter() - start
    start = time.perf_counter()
    lateral = []
    for v, m in list(zip(drawn["speed"], drawn["misalignment"]))[:count]:
        lateral.append(np.asarray(jax.block_until_ready(one(v, m)).wheelset_lateral))
    return compile_s, time.perf_counter() - start, np.stack(lateral)


def measure(scenario_name, samples, duration, seed, device_counts, sequential, contact):
    import jax

    from jaxrail import enable_float64

    enable_float64()
    from jaxrail.montecarlo import run_samples
    from jaxrail.scenarios import load_scenario

    scenario = load_scenario(scenario_name)
    built = scenario.build()
    drawn = study_inputs(scenario, samples, seed)
    report = {"host_devices": len(jax.devices()), "batches": []}
    if sequential:
        compile_s, run_s, lateral = one_after_another(scenario, built, drawn, duration,
                                                      contact)
        report |= {"sequential_compile_s": compile_s, "sequential_run_s": run_s,
                   "sequential_lateral": lateral.tolist()}
    for k in device_counts:
        batch = run_samples(scenario, drawn, duration=duration, chunk=samples, built=built,
                            keep_results=True, devices=jax.devices()[:k], contact=contact)
        report["batches"].append({
            "devices": k, "statuses": batch.statuses, "compile_s": batch.compile_time_s,
            "run_s": batch.run_time_s, "lateral": batch.results.wheelset_lateral.tolist()})
        print(json.dumps({k: v for k, v in report["batches"][-1].items() if k != "lateral"}),
              file=sys.stderr, flush=True)
    return report


def child(args, env, device_counts, sequential):
    """One configuration in a child process with environment ``env``."""
    command = [sys.executable, __file__, "--child", "--scenario", args.scenario,
               "--samples", str(args.samples), "--duration", str(args.duration),
               "--seed", str(args.seed), "--contact", args.contact,
               "--devices", *map(str, device_counts)]
    out = subprocess.run(command + (["--sequential"] if sequential else []), env=env,
                         stdout=subprocess.PIPE, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenario", default="bogie-curve-entry")
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--duration", type=float, default=0.25, help="[s] per sample")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--contact", choices=("online", "table"), default="online",
                        help="the paper's search or the contact table")
    parser.add_argument("--devices", type=int, nargs="*", default=[1, 2],
                        help="device counts to run the batch on (at most 2)")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--sequential", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(measure(args.scenario, args.samples, args.duration, args.seed,
                                 args.devices, args.sequential, args.contact)))
        return
    import numpy as np

    plain = child(args, dict(os.environ), [k for k in args.devices if k == 1], True)
    runs = [plain]
    if any(k > 1 for k in args.devices):
        env = dict(os.environ)
        env.update(host_device_environment(max(args.devices), env))
        runs.append(child(args, env, [k for k in args.devices if k > 1], False))
    simulated = args.samples * args.duration
    sequential = np.array(plain["sequential_lateral"])
    report = {"benchmark": "montecarlo", "cores": os.cpu_count(), "scenario": args.scenario,
              "contact": args.contact, "samples": args.samples, "duration_s": args.duration,
              "sequential_compile_s": plain["sequential_compile_s"],
              "sequential_run_s": plain["sequential_run_s"],
              "sequential_throughput": simulated / plain["sequential_run_s"], "batches": []}
    for run in runs:
        for batch in run["batches"]:
            lateral = np.array(batch.pop("lateral"))
            report["batches"].append(batch | {
                "host_devices": run["host_devices"], "throughput": simulated / batch["run_s"],
                "over_sequential": plain["sequential_run_s"] / batch["run_s"],
                "max_lateral_difference_m": float(np.nanmax(np.abs(sequential - lateral)))})
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
