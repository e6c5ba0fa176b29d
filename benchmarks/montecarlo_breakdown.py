"""Where a vmapped Monte Carlo batch gains over one run at a time: the initial static
equilibrium and the integration step, each alone and per member of a batch.

``python benchmarks/montecarlo_breakdown.py [--samples 64] [--scenario S]`` prints
JSON with, for one run and per member of a vmapped batch of ``--samples`` runs
(speeds 80-120 % of the scenario's, misalignments 0-4 mm): the time of the initial
equilibrium (:func:`jaxrail.vehicles.initial_state`) [s], and the time of one fixed
integration step [ms] (from runs of two lengths started at the equilibrium, so that
what does not grow with the steps cancels), with the ratios one / member. Run it with
the flags of the Monte Carlo benchmark to compare like with like, e.g.
``XLA_FLAGS=--xla_cpu_multi_thread_eigen=false``. ``--contact online|table`` chooses the contact
model (default the scenario's).
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

from jaxrail.scenarios import load_scenario  # noqa: E402
from jaxrail.simulation import solve  # noqa: E402
from jaxrail.vehicles import initial_state  # noqa: E402
from jaxrail.vehicles.loads import CONTACT_MODELS  # noqa: E402


def median_s(function, args, repeats):
    """Median wall time [s] of ``repeats`` calls of the compiled ``function``."""
    program = jax.jit(function).lower(*args).compile()
    jax.block_until_ready(program(*args))
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(program(*args))
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenario", default="bogie-curve-entry")
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--steps", type=int, nargs=2, default=[50, 150],
                        help="the two run lengths [fixed steps]")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--contact", choices=CONTACT_MODELS, default=None,
                        help="contact model (default: the scenario's)")
    args = parser.parse_args()
    scenario = load_scenario(args.scenario)
    vehicle, params, track = scenario.build()
    model = scenario.contact_model(vehicle, params, track, args.contact, True)
    options = scenario.solver_options()
    if options.fixed_step is None:
        raise SystemExit(f"{args.scenario}: needs a scenario with fixed steps")
    n = args.samples
    speeds = jnp.linspace(0.8, 1.2, n) * scenario.speed
    misalignments = jnp.linspace(0.0, 4e-3, n)

    def equilibrium(v, m):
        return initial_state(vehicle, params, track, v, m, model=model)

    init_one = median_s(equilibrium, (speeds[0], misalignments[0]), args.repeats)
    init_member = median_s(jax.vmap(equilibrium), (speeds, misalignments), args.repeats) / n
    start = jax.jit(jax.vmap(equilibrium))(speeds, misalignments)
    q0, qdot0 = start.q, start.qdot

    def run_time(steps, batched):
        duration = steps * options.fixed_step
        run_options = scenario.solver_options(duration=duration)

        def run(v, q, qdot):
            return solve(vehicle, params, track, duration, v, 0.0, options=run_options,
                         initial=(q, qdot), contact_model=model)

        if batched:
            return median_s(jax.vmap(run), (speeds, q0, qdot0), args.repeats) / n
        return median_s(run, (speeds[0], q0[0], qdot0[0]), args.repeats)

    short, long = args.steps
    step = {}
    for batched in (False, True):
        times = [run_time(k, batched) for k in (short, long)]
        step[batched] = (times[1] - times[0]) / (long - short)
    print(json.dumps({
        "benchmark": "montecarlo_breakdown", "scenario": scenario.name, "samples": n,
        "contact": model.name, "load": os.getloadavg(),
        "fixed_step_s": options.fixed_step, "run_lengths_steps": [short, long],
        "initial_equilibrium_s": {"one": init_one, "batch_member": init_member,
                                  "one_over_member": init_one / init_member},
        "integration_step_ms": {"one": 1e3 * step[False], "batch_member": 1e3 * step[True],
                                "one_over_member": step[False] / step[True]},
    }, indent=2))


if __name__ == "__main__":
    main()
