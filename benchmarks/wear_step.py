"""One step of a wear evolution (docs/wear.md): a route of ``--runs`` curve sections
(radii 300 to 1000 m with their cant, both hands, at 15 to 27 m/s) of ``--duration``
seconds each, the paper's trailer in table mode, batched (one vmapped program), and
the profile update after it.

``python benchmarks/wear_step.py [--runs 20] [--duration 10] [--contact table]``
prints JSON: the sections, the compile and run times of the batch [s] (the run includes
each run's wear, :func:`jaxrail.wear.run_wear`), the wear alone on the batch's results
(its own compiled program on results of the same shapes, every patch slot
active: an upper bound), the table build of the worn profile
that the next step needs, the profile measures' time, the device and the load.
"""

import argparse
import json
import os
import time

import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from jaxrail.simulation import WheelOutputs  # noqa: E402
from jaxrail.wear.run_wear import run_wear  # noqa: E402

from jaxrail.vehicles import contact_model  # noqa: E402
from jaxrail.wear.evolution import (GRID_SPACING, measured_wheel,  # noqa: E402
                                    profile_heights, profile_measures, route_wear,
                                    update_per_km)
from jaxrail.wear.distribution import lateral_grid  # noqa: E402
from jaxrail.wear.route import parse_route  # noqa: E402

RADII = (300.0, 400.0, 500.0, 600.0, 700.0, 800.0, 900.0, 1000.0, 1200.0, 1500.0)


def route_text(runs, duration):
    """A route of ``runs`` curves: radii from :data:`RADII`, both hands, cant 150 mm at
    300 m falling to 100 mm, speeds rising from 15 to 27 m/s."""
    lines = ['name = "benchmark-route"', 'scenario = "paper-curve"', f"duration = {duration}"]
    for k in range(runs):
        radius = RADII[(k // 2) % len(RADII)]
        share = (radius - 300.0) / 1200.0
        lines += ["[[sections]]", "weight = 1.0", f"radius = {radius}",
                  f"cant = {0.150 - 0.05 * share:.3f}",
                  f'direction = "{"left" if k % 2 == 0 else "right"}"',
                  f"speed = {15.0 + 12.0 * share:.2f}"]
    return "\n".join(lines) + "\n"


class _Outputs(eqx.Module):
    """What :func:`run_wear` reads of a result."""

    t: jax.Array
    valid: jax.Array
    q: jax.Array
    qdot: jax.Array
    wheels: WheelOutputs


def wear_alone(vehicle, params, law, runs, outputs, nodes, rail_nodes):
    """Compile and run times [s] of :func:`run_wear` vmapped over ``runs`` results of
    ``outputs`` times each, every patch slot active with tread-like values (60 kN, 6 x 5
    mm, partial slip): the wear's own cost beside the simulation's."""
    rng = np.random.default_rng(0)
    w, p = vehicle.n_wheelsets, 3
    shape = (runs, outputs, w, 2, p)
    f = lambda low, high: jnp.asarray(rng.uniform(low, high, shape))  # noqa: E731
    wheels = WheelOutputs(
        active=jnp.ones(shape, bool), surface=jnp.zeros(shape, jnp.int32),
        y_wheel=f(-0.005, 0.005), y_rail=f(-0.005, 0.005), penetration=f(5e-5, 1e-4),
        contact_angle=f(-0.05, 0.4), normal_force=f(2e4, 6e4), creep_force_x=f(-1e3, 1e3),
        creep_force_y=f(-1e3, 1e3), creepage_x=f(-3e-3, 3e-3), creepage_y=f(-3e-3, 3e-3),
        spin=f(-1.0, 1.0), semi_axis_a=f(4e-3, 7e-3), semi_axis_b=f(2e-3, 6e-3),
        lateral_force=jnp.zeros(shape[:-1]), vertical_force=jnp.zeros(shape[:-1]))
    n = vehicle.system.n_bodies
    q = jnp.tile(jnp.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]), n)
    qdot = jnp.tile(jnp.array([20.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]), n)
    result = _Outputs(t=jnp.broadcast_to(jnp.linspace(0.0, 10.0, outputs), (runs, outputs)),
                      valid=jnp.ones((runs, outputs), bool),
                      q=jnp.broadcast_to(q, (runs, outputs, 7 * n)),
                      qdot=jnp.broadcast_to(qdot, (runs, outputs, 7 * n)), wheels=wheels)
    wear = jax.jit(jax.vmap(lambda r: run_wear(r, vehicle, params, law, nodes, rail_nodes)))
    start = time.perf_counter()
    compiled = wear.lower(result).compile()
    compile_s = time.perf_counter() - start
    start = time.perf_counter()
    jax.block_until_ready(compiled(result))
    return compile_s, time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--duration", type=float, default=10.0)
    parser.add_argument("--contact", choices=("table", "online"), default="table")
    args = parser.parse_args()
    route = parse_route(route_text(args.runs, args.duration), "benchmark route")
    start = time.perf_counter()
    wear = route_wear(route, contact=args.contact)
    total_s = time.perf_counter() - start
    base = route.base()
    vehicle, params, track = base.build()
    nodes = lateral_grid(params.wheel.surfaces[0].domain, GRID_SPACING)
    loss = update_per_km(nodes, wear.wheel_depth_per_km) * 1000.0
    wheel = measured_wheel(nodes, profile_heights(params.wheel, nodes) - loss,
                           params.wheel.nominal_radius)
    start = time.perf_counter()
    measures = profile_measures(wheel, track.rails)
    measures_s = time.perf_counter() - start
    table_s = None
    if args.contact == "table":
        worn = eqx.tree_at(lambda p: p.wheel, params, wheel)
        start = time.perf_counter()
        contact_model("table", vehicle, worn, track, cache=False)
        table_s = time.perf_counter() - start
    rail_nodes = lateral_grid(track.rails.profile.domain, GRID_SPACING)
    outputs = base.solver_options(args.duration).n_outputs
    wear_compile_s, wear_run_s = wear_alone(vehicle, params, route.law(), args.runs, outputs,
                                            jnp.asarray(nodes), jnp.asarray(rail_nodes))
    print(json.dumps({
        "runs": args.runs, "duration_s": args.duration, "contact": args.contact,
        "simulated_s": args.runs * args.duration,
        "route_wear_s": total_s, "compile_s": wear.compile_s, "run_s": wear.run_s,
        "worn_table_build_s": table_s, "measures_s": measures_s,
        "wear_alone_compile_s": wear_compile_s, "wear_alone_run_s": wear_run_s,
        "outputs_per_run": outputs,
        "completed": int(np.sum(wear.completed)),
        "volume_per_km_leading_mm3": wear.volume_per_km[0].tolist(),
        "measures_after_1000_km": measures,
        "device": str(jax.devices()[0]), "load": os.getloadavg()}, indent=2))


if __name__ == "__main__":
    main()
