"""How often must IMEX evaluate its load Jacobian? The paper's curve with one every N
accepted steps.

IMEX keeps the wheel-rail loads' Jacobian J between refreshes and carries it to each
step's start by each wheelset's turn about its axle since (``StiffJacobian.turned``);
``SolverOptions.jacobian_every`` sets N (default 8). Each variant runs the paper's
curve (trailer, S1002 on UIC60 1:40, rigid rails, ``--contact``, default table mode)
for ``--duration`` seconds in a process of its own, with JAX's and jaxrail's caches
off:

- ``jN``: a new J every N accepted steps (``j1``: every step, as before the reuse);
- ``jN-unturned``: the same, the kept J used as it was (not turned with the wheelsets);
- ``j8-KenCarp4``, ``j8-KenCarp3``: KenCarp4 (6 stages) or KenCarp3 (4) instead of
  KenCarp5 (8), a new J every 8 accepted steps.

Prints JSON: per variant the compile time, the wall times of ``--runs`` runs after the
first (which compiles), steps accepted and rejected, load Jacobians and right-hand sides
(as the run counted them), µs per step attempt, and against ``j1``: the run's median
wall time, the largest difference of the wheelsets' lateral displacements [mm] and of
the outer wheel's normal force [% of its largest] over all output times; the load.

    python benchmarks/jacobian_reuse.py [--duration 1] [--runs 3] [--contact table]
        [--variants j1 j2 j8 j2-unturned]
"""

import argparse
import json
import os
import sys

from _variants import run_variant  # benchmarks/_variants.py, beside this script

VARIANTS = ("j1", "j2", "j4", "j8", "j16", "j32", "j2-unturned", "j8-unturned",
            "j8-KenCarp4", "j8-KenCarp3")
OUTER = 1  # the right wheel is the outer one in the paper's left curve


def child(variant, duration, runs, contact):
    """Run one variant; print its JSON row (with its outputs for the comparison)."""
    os.environ["JAXRAIL_COMPILATION_CACHE"] = "off"
    import dataclasses

    import numpy as np

    from jaxrail import enable_float64
    enable_float64()
    import jaxrail.simulation
    from jaxrail.multibody.imex import IMEX, StiffJacobian
    from jaxrail.scenarios import load_scenario, run_scenario

    every = int(variant.split("-")[0][1:])
    if variant.endswith("-unturned"):
        StiffJacobian.turned = lambda self, turns: self
    if "KenCarp" in variant:
        method = variant.split("-")[1]
        jaxrail.simulation.SolverOptions.solver = lambda self: IMEX(method, self.jacobian_every)
    scenario = dataclasses.replace(load_scenario("paper-curve"), integrator="imex",
                                   jacobian_every=every)
    first, *_ = run_scenario(scenario, duration, contact=contact)
    walls = []
    for _ in range(runs):
        result, *_ = run_scenario(scenario, duration, contact=contact)
        walls.append(float(result.wall_time_s))
    steps = int(result.steps)
    print(json.dumps({
        "variant": variant, "jacobian_every": every, "status": result.status,
        "method": variant.split("-")[1] if "KenCarp" in variant else "KenCarp5",
        "compile_s": round(float(first.compile_time_s), 1),
        "run_s": [round(w, 3) for w in walls], "run_s_median": round(float(np.median(walls)), 3),
        "steps_accepted": int(result.accepted_steps),
        "steps_rejected": int(result.rejected_steps),
        "jacobian_evaluations": int(result.jacobian_evaluations),
        "rhs_evaluations": int(result.rhs_evaluations),
        "us_per_step": round(1e6 * float(np.median(walls)) / steps, 1),
        "lateral": np.asarray(result.wheelset_lateral).tolist(),
        "outer_normal": np.nansum(np.asarray(result.wheels.normal_force)[:, :, OUTER],
                                  axis=-1).tolist()}))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1.0)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--contact", choices=("table", "online"), default="table")
    parser.add_argument("--variants", nargs="+", choices=VARIANTS, default=list(VARIANTS))
    parser.add_argument("--child", choices=VARIANTS)
    args = parser.parse_args()
    if args.runs < 1:
        parser.error("--runs must be at least 1")
    if args.child:
        return child(args.child, args.duration, args.runs, args.contact)
    import numpy as np
    rows = []
    for variant in args.variants:
        command = [sys.executable, __file__, "--child", variant, "--duration",
                   str(args.duration), "--runs", str(args.runs), "--contact", args.contact]
        rows.append(run_variant(command, variant))
        print(json.dumps({k: v for k, v in rows[-1].items()
                          if k not in ("lateral", "outer_normal")}), file=sys.stderr, flush=True)
    outputs = {r["variant"]: (np.asarray(r.pop("lateral")), np.asarray(r.pop("outer_normal")))
               for r in rows if "lateral" in r}
    base = next((r for r in rows if r["variant"] == "j1" and "error" not in r), None)
    for r in rows:
        if base is None or "error" in r:
            continue
        lateral, normal = outputs[r["variant"]]
        lateral1, normal1 = outputs["j1"]
        r["lateral_vs_j1_mm"] = float(1e3 * np.nanmax(np.abs(lateral - lateral1)))
        r["outer_normal_vs_j1_percent"] = float(
            100 * np.nanmax(np.abs(normal - normal1)) / np.nanmax(normal1))
        r["run_time_vs_j1"] = round(r["run_s_median"] / base["run_s_median"], 3)
    print(json.dumps({"benchmark": "jacobian_reuse", "scenario": "paper-curve",
                      "contact": args.contact, "duration_s": args.duration, "variants": rows,
                      "cpus": os.cpu_count(), "load_1min_after": round(os.getloadavg()[0], 2)},
                     indent=1))


if __name__ == "__main__":
    main()
