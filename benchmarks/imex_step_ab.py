"""One IMEX step of an earlier commit against the working tree's, in one process.

The trailer at the paper curve's start (rigid rails), one KenCarp5 step of 1 ms in a
compiled loop of 50 chained steps, as ``benchmarks/rhs_profile.py`` times its
``imex_step``: the module ``jaxrail/multibody/imex.py`` of ``--against`` (a git
revision) is loaded beside the working tree's, both are compiled, and their timings are
interleaved over ``--rounds`` rounds so that the machine's drift falls on both alike.
Both steps take the one term (``VehicleLoads``) as diffrax's ``args``, so ``--against``
must be a revision whose IMEX does too (from the commit that made the system, its
parameters and the loads one term, ``jaxrail.multibody.AbstractLoads``, on).
Prints JSON: the median µs per step of each, their ratio, the operations in each
optimised program, the relative difference of the loop's output sums, and the load.

    python benchmarks/imex_step_ab.py --against HEAD~1 --rounds 7
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import types
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
import rhs_profile as profile  # noqa: E402  (float64 and the benchmark's helpers)

import diffrax  # noqa: E402
import equinox as eqx  # noqa: E402
import jax  # noqa: E402

import jaxrail.multibody.imex as working  # noqa: E402
from jaxrail.multibody import rhs as multibody_rhs  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def module_at(revision):
    """``jaxrail.multibody.imex`` as it was at the git ``revision``."""
    source = subprocess.run(["git", "-C", str(ROOT), "show",
                             f"{revision}:jaxrail/multibody/imex.py"],
                            capture_output=True, text=True, check=True).stdout
    module = types.ModuleType("jaxrail.multibody.imex_at_revision")
    module.__package__ = "jaxrail.multibody"
    exec(compile(source, f"imex.py@{revision}", "exec"), module.__dict__)
    return module


def compiled_steps(module, q, qdot, data, structure):
    """The compiled loop of chained IMEX steps of ``module``'s solver
    (:func:`rhs_profile.compiled_loop`)."""
    def step(q, qdot, data):
        vehicle, params, track, model = eqx.combine(data, structure)
        loads = profile.VehicleLoads(vehicle, params, track, model)
        return module.IMEX().step(diffrax.ODETerm(multibody_rhs), 0.0, profile.IMEX_STEP,
                                  profile.State.of(q, qdot), loads, None, False)[0]

    return profile.compiled_loop(step, (q, qdot, data))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--against", default="HEAD", help="git revision of the other step")
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args()
    earlier = module_at(args.against)
    scenario = profile.load_scenario("paper-curve")
    vehicle, params, track = scenario.build()
    table, _ = profile.contact_table(params.wheel, track.rails, vehicle.config)
    start = jax.jit(lambda p, t: profile.initial_state(
        vehicle, p, t, scenario.speed, scenario.misalignment))(params, track)
    q, qdot = start.q, start.qdot
    out = {"benchmark": "imex_step_ab", "against": args.against, "rounds": args.rounds,
           "load_before": os.getloadavg()}
    for name, model in (("table", profile.TableContact(table)),
                        ("online", profile.OnlineContact())):
        data, structure = eqx.partition((vehicle, params, track, model), eqx.is_array)
        programs = {label: compiled_steps(module, q, qdot, data, structure)
                    for label, module in (("against", earlier), ("working", working))}
        sums = {label: float(program(q, qdot, data)) for label, program in programs.items()}
        times = {label: [] for label in programs}
        for _ in range(args.rounds):
            for label, program in programs.items():
                times[label].append(1e6 * profile._median_call_s(program, (q, qdot, data), 5)
                                    / profile.LOOP_REPEATS)
        us = {label: round(statistics.median(t), 1) for label, t in times.items()}
        out[name] = {"step_us": us, "working_over_against": round(us["working"] / us["against"], 3),
                     "operations": {label: profile.operation_counts(p)["operations"]
                                    for label, p in programs.items()},
                     "loop_sums_rel_diff": abs(sums["working"] - sums["against"])
                     / abs(sums["against"])}
    out["load_after"] = os.getloadavg()
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
