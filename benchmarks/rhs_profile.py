"""Where the time of one right-hand-side evaluation goes, alone and in a batch.

Times (median of ``--calls`` jitted calls, after compilation) at the initial state of
a scenario (default ``paper-curve``, the trailer): the contact search of all wheels,
the search plus the force laws (``contact_loads``), the multibody part alone (eq. 19
without wheel-rail loads: mass matrix, constraints, force elements, the augmented
solve), and the whole right-hand side. With ``--batch N`` also the whole right-hand
side vmapped over N states (the initial one with the whole vehicle shifted along the global
y axis by 0-4 mm) per member, and its ratio to one call: what batching gains per evaluation.
Prints JSON with the times [ms] and their shares.
Usage: ``python benchmarks/rhs_profile.py [--calls 200] [--scenario S] [--batch N]``.
"""

import argparse
import json
import os
import statistics
import time

import jax
import jax.numpy as jnp

from jaxrail import enable_float64

enable_float64()

from jaxrail.contact import search_vehicle  # noqa: E402
from jaxrail.multibody import accelerations  # noqa: E402
from jaxrail.scenarios import load_scenario  # noqa: E402
from jaxrail.vehicles import contact_loads, initial_state  # noqa: E402
from jaxrail.vehicles.vehicle import wheelset_states  # noqa: E402


def median_ms(function, args, calls):
    compiled = jax.jit(function).lower(*args).compile()
    jax.block_until_ready(compiled(*args))
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        jax.block_until_ready(compiled(*args))
        times.append(time.perf_counter() - start)
    return 1e3 * statistics.median(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--calls", type=int, default=200)
    parser.add_argument("--scenario", default="paper-curve")
    parser.add_argument("--batch", type=int, default=0, help="members of a vmapped batch")
    args = parser.parse_args()
    scenario = load_scenario(args.scenario)
    vehicle, params, track = scenario.build()
    q, qdot = jax.jit(lambda p: initial_state(vehicle, p, track, scenario.speed,
                                              scenario.misalignment))(params)

    def search(q, qdot):
        position, rotation, _, _ = wheelset_states(vehicle, q, qdot)
        return search_vehicle(vehicle.wheel, vehicle.rail, track, vehicle.rail_offset,
                              position, rotation, vehicle.config).penetration

    def loads(q, qdot):
        return contact_loads(vehicle, params.contact, track, q, qdot)[:2]

    def multibody(q, qdot):
        return accelerations(vehicle.system, params.system, 0.0, q, qdot)[0]

    def rhs(q, qdot):
        return accelerations(vehicle.system, params.system, 0.0, q, qdot,
                             lambda t, q, qdot: loads(q, qdot))[0]

    times = {name: median_ms(f, (q, qdot), args.calls) for name, f in
             (("contact_search", search), ("contact_loads", loads),
              ("multibody_only", multibody), ("rhs", rhs))}
    batched = {}
    if args.batch:
        shifts = jnp.linspace(0.0, 4e-3, args.batch)
        q_batch = jax.vmap(lambda d: q.reshape(-1, 7).at[:, 1].add(d).reshape(-1))(shifts)
        qdot_batch = jnp.broadcast_to(qdot, (args.batch,) + qdot.shape)
        member = median_ms(jax.vmap(rhs), (q_batch, qdot_batch), args.calls) / args.batch
        batched = {"batch": args.batch, "rhs_per_member_ms": round(member, 4),
                   "one_over_member": round(times["rhs"] / member, 3)}
    total = times["rhs"]
    print(json.dumps({
        "benchmark": "rhs_profile", "scenario": scenario.name, "calls": args.calls,
        "median_ms": {k: round(v, 4) for k, v in times.items()}, **batched,
        "share_of_rhs": {
            "contact_search": round(times["contact_search"] / total, 3),
            "force_laws": round((times["contact_loads"] - times["contact_search"]) / total, 3),
            "multibody": round(times["multibody_only"] / total, 3),
        },
        "load": os.getloadavg(), "jnp_dtype": str(jnp.zeros(1).dtype),
    }, indent=2))


if __name__ == "__main__":
    main()
