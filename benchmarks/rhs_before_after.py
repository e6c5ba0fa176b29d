"""The trailer's right-hand side and IMEX step of an earlier revision against the
working tree's, in alternating processes.

Each process times one variant as ``benchmarks/rhs_profile.py`` does (that revision's
own script and package: the whole right-hand side, :func:`jaxrail.vehicles.vehicle_accelerations`,
one KenCarp5 step of 1 ms with a new load Jacobian and one that keeps an earlier one
(turned with the wheelsets, as 7 of 8 steps do in a run), each in a compiled loop of 50,
median of ``--calls`` loops, at the paper curve's start on rigid rails). The variants
run in turn, ``--rounds`` times, so that the machine's drift falls on all alike:
``before`` (``--against``, checked out into a temporary ``git worktree``, as it was),
``after`` (the working tree as the Python API compiles it) and ``after-kernels`` (with
XLA's small-while-loop threshold raised, as ``jaxrail simulate`` runs it:
:mod:`jaxrail.compilation.loop_kernels`). Prints JSON: per contact model and variant
the median over the rounds of each time [us] and the ratios of ``before`` to each
``after``, with the load. Usage: ``python benchmarks/rhs_before_after.py --against
09cf02a [--rounds 3] [--contacts table online]``.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from _worktree import ROOT, revision_tree

from jaxrail.compilation.loop_kernels import THRESHOLD_FLAG

# one variant in a process of its own, with the tree's own package and rhs_profile
TIME = """
import json, sys
sys.path[:0] = [{root!r}, {root!r} + "/benchmarks"]
import jax, jax.numpy as jnp, diffrax, equinox as eqx
import rhs_profile as rp
from jaxrail.scenarios import load_scenario
from jaxrail.contact.table_cache import contact_table
from jaxrail.multibody import State, rhs as multibody_rhs
from jaxrail.multibody.imex import IMEX, stiff_jacobian
from jaxrail.vehicles import OnlineContact, TableContact, VehicleLoads, initial_state, vehicle_accelerations
scenario = load_scenario("paper-curve")
vehicle, params, track = scenario.build()
if {contact!r} == "table":
    model = TableContact(contact_table(params.wheel, track.rails, vehicle.config)[0])
else:
    model = OnlineContact()
state = jax.jit(lambda p, t: initial_state(vehicle, p, t, scenario.speed, scenario.misalignment))(params, track)
data, structure = eqx.partition((vehicle, params, track, model), eqx.is_array)
def rhs(q, qdot, data):
    vehicle, params, track, model = eqx.combine(data, structure)
    return vehicle_accelerations(vehicle, params, track, 0.0, q, qdot, model)
def step(q, qdot, data):
    vehicle, params, track, model = eqx.combine(data, structure)
    loads = VehicleLoads(vehicle, params, track, model)
    y0 = State.of(q, qdot, None)
    return IMEX().step(diffrax.ODETerm(multibody_rhs), 0.0, 1e-3, y0, loads, None, False)[0]
def jacobian(q, qdot, data):
    vehicle, params, track, model = eqx.combine(data, structure)
    return stiff_jacobian(0.0, State.of(q, qdot, None), VehicleLoads(vehicle, params, track, model))[1]
args = (state.q, state.qdot, data)
kept = jax.jit(jacobian)(*args)
def step_kept(q, qdot, data):
    vehicle, params, track, model = eqx.combine(data, structure)
    loads, y0 = VehicleLoads(vehicle, params, track, model), State.of(q, qdot, None)
    solver, term = IMEX(jacobian_every=8), diffrax.ODETerm(multibody_rhs)
    euler = solver.init(term, 0.0, 1e-3, y0, loads)[2]
    age = jnp.where(q[0] > 1e30, 8, 1).astype(jnp.int32)  # run-time: both branches stay
    return solver.step(term, 0.0, 1e-3, y0, loads, (kept, age, euler), False)[0]
print(json.dumps({{"rhs_us": rp.timed_in_loop(rhs, args, {calls})[0],
                  "imex_step_us": rp.timed_in_loop(step, args, {calls})[0],
                  "imex_step_kept_jacobian_us": rp.timed_in_loop(step_kept, args, {calls})[0]}}))
"""

KEYS = ("rhs_us", "imex_step_us", "imex_step_kept_jacobian_us")


def time_variant(root, contact, calls, loop_kernels):
    """{"rhs_us", "imex_step_us", "imex_step_kept_jacobian_us"} of the tree at ``root``
    in a fresh process."""
    env = dict(os.environ, JAXRAIL_COMPILATION_CACHE="off")
    env.pop("XLA_FLAGS", None)
    if loop_kernels:
        env["XLA_FLAGS"] = THRESHOLD_FLAG
    code = TIME.format(root=str(root), contact=contact, calls=calls)
    done = subprocess.run([sys.executable, "-c", code], env=env, check=True,
                          capture_output=True, text=True, cwd=tempfile.gettempdir())
    return json.loads(done.stdout.splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--against", required=True, help="git revision before the change")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--calls", type=int, default=20)
    parser.add_argument("--contacts", nargs="+", default=["table", "online"],
                        choices=("table", "online"))
    args = parser.parse_args()
    out = {"benchmark": "rhs_before_after", "against": args.against, "rounds": args.rounds,
           "working_tree": subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, check=True,
                                          capture_output=True, text=True).stdout.strip(),
           "load_before": os.getloadavg()}
    with tempfile.TemporaryDirectory() as folder, \
            revision_tree(args.against, Path(folder) / "before") as before:
        variants = {"before": (before, False), "after": (ROOT, False),
                    "after-kernels": (ROOT, True)}
        for contact in args.contacts:
            times = {name: [] for name in variants}
            for _ in range(args.rounds):
                for name, (root, kernels) in variants.items():
                    times[name].append(time_variant(root, contact, args.calls, kernels))
            medians = {name: {key: round(statistics.median(t[key] for t in runs), 1)
                              for key in KEYS}
                       for name, runs in times.items()}
            out[contact] = {
                "median_us": medians,
                "all_us": times,
                "before_over": {name: {key: round(medians["before"][key] / m[key], 2)
                                       for key in m}
                                for name, m in medians.items() if name != "before"},
            }
            print(json.dumps({contact: out[contact]["median_us"]}), file=sys.stderr)
    out["load_after"] = os.getloadavg()
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
