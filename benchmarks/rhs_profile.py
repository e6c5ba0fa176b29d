"""Where the time of one right-hand-side evaluation goes, per contact model.

For each contact model (``online``, the paper's search, and ``table``, its table, built
and cached first if needed, with the build time reported) the median of ``--calls``
jitted calls, after compilation, at the initial state of a scenario (default
``paper-curve``, the trailer):

- ``contact_us``: the contact patches of all wheels (the search, or the table lookup);
- ``loads_us``: the patches and the force laws (:func:`jaxrail.vehicles.contact_loads`);
  ``force_laws_us`` is its difference to ``contact_us``;
- ``multibody_us``: eq. (19) without wheel-rail loads (mass matrix, constraints,
  force elements, the solve);
- ``rhs_median_us``: the whole right-hand side (:func:`jaxrail.vehicles.vehicle_accelerations`);
- ``compile_s``: the compile time of each of these programs.

With ``--batch N`` also the whole right-hand side vmapped over N states (the initial
one with the whole vehicle shifted along the global y axis by 0-4 mm), per member.
Prints one JSON object with an object per model and ``online_over_table``.
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

from jaxrail.multibody import accelerations  # noqa: E402
from jaxrail.scenarios import load_scenario  # noqa: E402
from jaxrail.contact.table_cache import contact_table  # noqa: E402
from jaxrail.vehicles import (OnlineContact, TableContact, contact_loads,  # noqa: E402
                              initial_state, vehicle_accelerations)
from jaxrail.vehicles.vehicle import wheelset_states  # noqa: E402


def timed(function, args, calls):
    """(median run time [us], compile time [s]) of ``jax.jit(function)(*args)``."""
    start = time.perf_counter()
    compiled = jax.jit(function).lower(*args).compile()
    compile_s = time.perf_counter() - start
    jax.block_until_ready(compiled(*args))
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        jax.block_until_ready(compiled(*args))
        times.append(time.perf_counter() - start)
    return 1e6 * statistics.median(times), compile_s


def profile_model(model, vehicle, params, track, q, qdot, calls, batch):
    """The JSON object of one contact model."""

    def contact(q, qdot):
        position, rotation, _, _ = wheelset_states(vehicle, q, qdot)
        return jax.vmap(lambda r, a: model.wheelset_patches(vehicle, track, r, a))(
            position, rotation).penetration

    def loads(q, qdot):
        return contact_loads(vehicle, params.contact, track, q, qdot, model)[:2]

    def multibody(q, qdot):
        return accelerations(vehicle.system, params.system, 0.0, q, qdot)[0]

    def rhs(q, qdot):
        return vehicle_accelerations(vehicle, params, track, 0.0, q, qdot, model)

    parts = {name: timed(f, (q, qdot), calls) for name, f in
             (("contact", contact), ("loads", loads), ("multibody", multibody), ("rhs", rhs))}
    out = {
        "rhs_median_us": round(parts["rhs"][0], 1),
        "contact_us": round(parts["contact"][0], 1),
        "force_laws_us": round(parts["loads"][0] - parts["contact"][0], 1),
        "loads_us": round(parts["loads"][0], 1),
        "multibody_us": round(parts["multibody"][0], 1),
        "compile_s": {name: round(value[1], 2) for name, value in parts.items()},
    }
    if batch:
        shifts = jnp.linspace(0.0, 4e-3, batch)
        q_batch = jax.vmap(lambda d: q.reshape(-1, 7).at[:, 1].add(d).reshape(-1))(shifts)
        qdot_batch = jnp.broadcast_to(qdot, (batch,) + qdot.shape)
        member = timed(jax.vmap(rhs), (q_batch, qdot_batch), calls)[0] / batch
        out.update(batch=batch, rhs_per_member_us=round(member, 1),
                   one_over_member=round(parts["rhs"][0] / member, 3))
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--calls", type=int, default=200)
    parser.add_argument("--scenario", default="paper-curve")
    parser.add_argument("--batch", type=int, default=0, help="members of a vmapped batch")
    args = parser.parse_args()
    scenario = load_scenario(args.scenario)
    vehicle, params, track = scenario.build()
    table, table_info = contact_table(vehicle.wheel, vehicle.rail, vehicle.rail_offset,
                                      vehicle.config, progress=True)
    models = {"online": OnlineContact(), "table": TableContact(table)}
    q, qdot = jax.jit(lambda p: initial_state(vehicle, p, track, scenario.speed,
                                              scenario.misalignment))(params)
    results = {name: profile_model(model, vehicle, params, track, q, qdot, args.calls,
                                   args.batch) for name, model in models.items()}
    results["table"]["table"] = {key: table_info[key] for key in
                                 ("build_time_s", "cached", "nodes", "level_misses", "path")
                                 if key in table_info}
    ratio = {"online_over_table": round(results["online"]["rhs_median_us"]
                                        / results["table"]["rhs_median_us"], 2)}
    print(json.dumps({
        "benchmark": "rhs_profile", "scenario": scenario.name, "calls": args.calls,
        **results, **ratio, "load": os.getloadavg(), "jnp_dtype": str(jnp.zeros(1).dtype),
    }, indent=2))


if __name__ == "__main__":
    main()
