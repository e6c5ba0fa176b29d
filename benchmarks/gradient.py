"""Cost of one gradient of the identification loss against one forward run.

Scenario ``bogie-curve-entry`` (1 s, fixed 0.5 ms steps, a bogie on the flange root
from 0.6 s); loss: the whitened least squares of experiments/identify_contact against
its own noise-free truth, at parameters 10 % off; gradient with respect to the contact
stiffness scale and the friction coefficient by reverse mode through diffrax.

Three ways: reverse mode with recursive checkpointing, one checkpoint per step
(``per_step``: no recomputation, memory grows with the steps) or diffrax's default
number of checkpoints for ``max_steps`` (``default``: memory bounded, recomputes); and
forward mode (``forward``: one Jacobian-vector product per parameter through diffrax's
``ForwardMode``, the gradient J^T r; what the fits of a few parameters use). Prints JSON:
compile times, median run times of ``--repeats`` runs, the ratio gradient / forward,
and XLA's memory analysis of each compiled program (arguments + outputs + temporaries)
with the process's peak resident memory.
Usage: ``python benchmarks/gradient.py [--repeats 3] [--adjoints per_step,default,forward]``.
"""

import argparse
import json
import os
import resource
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

from jaxrail import enable_float64

enable_float64()

import diffrax  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "experiments",
                                "identify_contact"))
from run import CHANNELS, FIT, SCENARIO, truth  # noqa: E402

from jaxrail.identification import get_values, simulation_residuals  # noqa: E402
from jaxrail.identification.fit import loss_gradient_jacobian  # noqa: E402
from jaxrail.scenarios import load_scenario  # noqa: E402


def compiled(function, x):
    start = time.perf_counter()
    program = jax.jit(function).lower(x).compile()
    return program, time.perf_counter() - start


def median_time(program, x, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(program(x))
        times.append(time.perf_counter() - start)
    return float(np.median(times)), times


def memory(program):
    analysis = program.memory_analysis()
    if analysis is None:
        return None
    return {"argument_bytes": analysis.argument_size_in_bytes,
            "output_bytes": analysis.output_size_in_bytes,
            "temp_bytes": analysis.temp_size_in_bytes,
            "total_mb": (analysis.argument_size_in_bytes + analysis.output_size_in_bytes
                         + analysis.temp_size_in_bytes) / 2**20}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--adjoints", default="per_step,default,forward")
    args = parser.parse_args()
    scenario = load_scenario(SCENARIO)
    (vehicle, params, track), measured = truth(scenario)
    options = scenario.solver_options()
    x = jnp.asarray(np.asarray(get_values(vehicle, params, FIT)) * 1.1)
    data = jnp.asarray(measured.values)
    report = {"scenario": SCENARIO, "duration_s": scenario.duration,
              "fixed_step_s": options.fixed_step, "steps": options.max_steps - 1,
              "parameters": list(FIT), "channels": list(CHANNELS),
              "samples": len(measured.time), "repeats": args.repeats,
              "devices": [str(d) for d in jax.devices()], "adjoints": {}}
    common = dict(speed=scenario.speed, misalignment=scenario.misalignment,
                  duration=scenario.duration, options=options)
    forward_residuals = simulation_residuals(vehicle, params, track, FIT, measured, **common)
    loss = lambda v, r=forward_residuals: 0.5 * jnp.sum(r(v, data) ** 2)  # noqa: E731
    forward, forward_compile = compiled(loss, x)
    forward_time, forward_times = median_time(forward, x, args.repeats)
    report["forward"] = {"compile_s": forward_compile, "run_s_median": forward_time,
                         "run_s": forward_times, "memory": memory(forward)}
    print(json.dumps(report["forward"]), file=sys.stderr, flush=True)
    for name in args.adjoints.split(","):
        if name == "forward":
            residuals = simulation_residuals(vehicle, params, track, FIT, measured,
                                             forward=True, **common)
            gradient, gradient_compile = compiled(
                lambda v, r=residuals: loss_gradient_jacobian(lambda v: r(v, data), v)[:2], x)
        else:
            adjoint = (diffrax.RecursiveCheckpointAdjoint(checkpoints=options.max_steps)
                       if name == "per_step" else diffrax.RecursiveCheckpointAdjoint())
            residuals = simulation_residuals(vehicle, params, track, FIT, measured,
                                             adjoint=adjoint, **common)
            gradient, gradient_compile = compiled(
                jax.value_and_grad(lambda v, r=residuals: 0.5 * jnp.sum(r(v, data) ** 2)), x)
        gradient_time, gradient_times = median_time(gradient, x, args.repeats)
        report["adjoints"][name] = {
            "compile_s": gradient_compile, "run_s_median": gradient_time,
            "run_s": gradient_times, "gradient_over_forward": gradient_time / forward_time,
            "memory": memory(gradient)}
        print(json.dumps(report["adjoints"][name]), file=sys.stderr, flush=True)
    report["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
