"""Where the time of one right-hand-side evaluation of the trailer goes.

Times (median of ``--calls`` jitted calls, after compilation) at the initial state of
the ``paper-curve`` scenario: the contact search of the 8 wheels, the search plus the
force laws (``contact_loads``), the multibody part alone (eq. 19 without wheel-rail
loads: mass matrix, constraints, force elements, the augmented solve), and the whole
right-hand side. Prints JSON with the times [ms] and their shares.
Usage: ``python benchmarks/rhs_profile.py [--calls 200]``.
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
    args = parser.parse_args()
    scenario = load_scenario("paper-curve")
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
    total = times["rhs"]
    print(json.dumps({
        "benchmark": "rhs_profile", "scenario": scenario.name, "calls": args.calls,
        "median_ms": {k: round(v, 4) for k, v in times.items()},
        "share_of_rhs": {
            "contact_search": round(times["contact_search"] / total, 3),
            "force_laws": round((times["contact_loads"] - times["contact_search"]) / total, 3),
            "multibody": round(times["multibody_only"] / total, 3),
        },
        "load": os.getloadavg(), "jnp_dtype": str(jnp.zeros(1).dtype),
    }, indent=2))


if __name__ == "__main__":
    main()
